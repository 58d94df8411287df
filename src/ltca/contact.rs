//! The frictionless contact problem of one mesh position, solved exactly by a primal active-set
//! method (Nocedal & Wright, *Numerical Optimization*, 2nd ed., §16.5).
//!
//! Unknowns: contact forces F ≥ 0 at the candidate points and the driven gear's rigid rotation φ.
//! ```text
//! gap after loading   g = g₀ + C F − φ a ≥ 0,   F ≥ 0,   Fᵢ gᵢ = 0     (no penetration, no tension)
//! torque balance      aᵀ F = T
//! ```
//! C is the (symmetric positive definite) compliance of both bodies between the candidate points,
//! a the gap-closing rate per unit rotation (the moment arm). These are the KKT conditions of
//! ```text
//! min ½ Fᵀ C F + g₀ᵀ F   subject to   aᵀ F = T,  F ≥ 0
//! ```
//! with φ the multiplier of the torque constraint and g the multipliers of F ≥ 0, so the QP's
//! solution is the contact solution and φ is the loaded static transmission error.

use nalgebra::{DMatrix, DVector};

/// Outcome statistics of a contact solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSolution {
    /// Driven-gear rotation φ that closes the gaps under load [rad].
    pub rotation: f64,
    /// Active-set iterations.
    pub iterations: usize,
    /// Largest KKT violation, relative: max(penetration, tension, |complementarity|, torque
    /// error) over the natural scales (gap scale g_s = max|C F|, force scale T/min a).
    pub kkt_residual: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    #[error(
        "the contact problem has no candidate that can carry the torque (all moment arms ≤ 0)"
    )]
    NoCandidate,
    #[error("the active-set contact solve did not converge in {iterations} iterations (KKT residual {residual:.3e})")]
    NotConverged { iterations: usize, residual: f64 },
    #[error("the contact subproblem is singular on the active set (a compliance matrix that is not positive definite)")]
    Singular,
}

/// Solves the contact problem; writes the forces into `forces` (length n).
pub fn solve_contact(
    compliance: &DMatrix<f64>,
    initial_gap: &DVector<f64>,
    arm: &DVector<f64>,
    torque: f64,
    forces: &mut DVector<f64>,
) -> Result<ContactSolution, ContactError> {
    let n = initial_gap.len();
    forces.fill(0.0);
    // Start: the single point that closes first under rotation, carrying the whole torque.
    let first = (0..n)
        .filter(|&k| arm[k] > 0.0)
        .min_by(|&i, &j| (initial_gap[i] / arm[i]).total_cmp(&(initial_gap[j] / arm[j])))
        .ok_or(ContactError::NoCandidate)?;
    let mut active = vec![first];
    forces[first] = torque / arm[first];
    let mut rotation = 0.0;
    let gap_scale = |f: &DVector<f64>| (compliance * f).amax().max(1e-30);
    let max_iterations = 10 * n + 20;
    for iteration in 0..max_iterations {
        // Equality-constrained subproblem on the active set:
        // [C_SS  −a_S] [F_S]   [−g₀_S]
        // [a_Sᵀ   0  ] [ φ ] = [  T  ]
        let m = active.len();
        let mut kkt = DMatrix::<f64>::zeros(m + 1, m + 1);
        let mut rhs = DVector::<f64>::zeros(m + 1);
        for (i, &p) in active.iter().enumerate() {
            for (j, &q) in active.iter().enumerate() {
                kkt[(i, j)] = compliance[(p, q)];
            }
            kkt[(i, m)] = -arm[p];
            kkt[(m, i)] = arm[p];
            rhs[i] = -initial_gap[p];
        }
        rhs[m] = torque;
        let solution = kkt.lu().solve(&rhs).ok_or(ContactError::Singular)?;
        let candidate: Vec<f64> = (0..m).map(|i| solution[i]).collect();
        if candidate.iter().all(|f| *f >= 0.0) {
            for (i, &p) in active.iter().enumerate() {
                forces[p] = candidate[i];
            }
            rotation = solution[m];
            // Most penetrating inactive point, if any.
            let gaps = initial_gap + compliance * &*forces - arm * rotation;
            let tolerance = 1e-12 * gap_scale(forces);
            let worst = (0..n)
                .filter(|k| !active.contains(k))
                .min_by(|&i, &j| gaps[i].total_cmp(&gaps[j]));
            match worst {
                Some(k) if gaps[k] < -tolerance => active.push(k),
                _ => {
                    let kkt_residual =
                        kkt_residual(compliance, initial_gap, arm, torque, forces, rotation);
                    return Ok(ContactSolution {
                        rotation,
                        iterations: iteration + 1,
                        kkt_residual,
                    });
                }
            }
        } else {
            // Step from the current forces towards the candidate until a force reaches zero,
            // then drop the points at zero.
            let mut step = 1.0_f64;
            for (i, &p) in active.iter().enumerate() {
                if candidate[i] < 0.0 {
                    step = step.min(forces[p] / (forces[p] - candidate[i]));
                }
            }
            for (i, &p) in active.iter().enumerate() {
                forces[p] += step * (candidate[i] - forces[p]);
            }
            let floor = 1e-14 * forces.amax();
            active.retain(|&p| {
                let keep = forces[p] > floor;
                if !keep {
                    forces[p] = 0.0;
                }
                keep
            });
            if active.is_empty() {
                return Err(ContactError::Singular);
            }
        }
    }
    let residual = kkt_residual(compliance, initial_gap, arm, torque, forces, rotation);
    Err(ContactError::NotConverged {
        iterations: max_iterations,
        residual,
    })
}

/// Relative KKT residual of a candidate solution (see [`ContactSolution::kkt_residual`]).
pub fn kkt_residual(
    compliance: &DMatrix<f64>,
    initial_gap: &DVector<f64>,
    arm: &DVector<f64>,
    torque: f64,
    forces: &DVector<f64>,
    rotation: f64,
) -> f64 {
    let elastic = compliance * forces;
    let gaps = initial_gap + &elastic - arm * rotation;
    let gap_scale = elastic.amax().max(1e-30);
    let force_scale = torque
        / arm
            .iter()
            .copied()
            .fold(f64::INFINITY, |a, b| if b > 0.0 { a.min(b) } else { a });
    let mut worst = ((arm.dot(forces) - torque) / torque).abs();
    for k in 0..forces.len() {
        worst = worst.max((-gaps[k]).max(0.0) / gap_scale);
        worst = worst.max((-forces[k]).max(0.0) / force_scale);
        worst = worst.max((forces[k] / force_scale) * (gaps[k].abs() / gap_scale));
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth SPD compliance between points along a line, like the flank's influence matrix.
    fn compliance(n: usize) -> DMatrix<f64> {
        DMatrix::from_fn(n, n, |i, j| {
            let d = (i as f64 - j as f64).abs();
            1e-9 * (1.0 / (1.0 + 0.3 * d) + if i == j { 0.5 } else { 0.0 })
        })
    }

    #[test]
    fn two_springs_in_parallel_share_the_load_by_stiffness() {
        // Diagonal compliance: two independent springs with equal arms, both closed.
        let c = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-9, 3e-9]));
        let g0 = DVector::zeros(2);
        let a = DVector::from_vec(vec![0.05, 0.05]);
        let mut f = DVector::zeros(2);
        let sol = solve_contact(&c, &g0, &a, 100.0, &mut f).unwrap();
        // W = T/a = 2000 N, split 3:1 (stiffness 1/c), rotation = c₁F₁/a.
        assert!((f[0] - 1500.0).abs() < 1e-9 && (f[1] - 500.0).abs() < 1e-9);
        assert!((sol.rotation - 1e-9 * 1500.0 / 0.05).abs() < 1e-15);
        assert!(sol.kkt_residual < 1e-12);
    }

    #[test]
    fn an_initial_gap_larger_than_the_deflection_stays_open() {
        let c = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-9, 1e-9]));
        let g0 = DVector::from_vec(vec![0.0, 1e-3]);
        let a = DVector::from_vec(vec![0.05, 0.05]);
        let mut f = DVector::zeros(2);
        solve_contact(&c, &g0, &a, 100.0, &mut f).unwrap();
        assert_eq!(f[1], 0.0);
        assert!((f[0] - 2000.0).abs() < 1e-9);
    }

    #[test]
    fn no_candidate_with_a_moment_arm_is_a_clear_error() {
        let c = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-9, 1e-9]));
        let g0 = DVector::zeros(2);
        let a = DVector::from_vec(vec![-0.05, 0.0]);
        let mut f = DVector::zeros(2);
        let err = solve_contact(&c, &g0, &a, 100.0, &mut f).unwrap_err();
        assert_eq!(err, ContactError::NoCandidate);
        assert!(err.to_string().contains("no candidate"));
    }

    /// Against brute force: every subset of active points, keep the one that satisfies all KKT
    /// conditions; it must equal the active-set answer.
    /// A compliance that is not positive definite (the second point's negative) makes the active
    /// set's KKT system singular: a named error, not a wrong force.
    #[test]
    fn a_singular_contact_subproblem_is_a_clear_error() {
        let compliance = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        let gap = DVector::from_vec(vec![0.0, 0.0]);
        let arm = DVector::from_vec(vec![1.0, 1.0]);
        let mut forces = DVector::zeros(2);
        let err = solve_contact(&compliance, &gap, &arm, 1.0, &mut forces).unwrap_err();
        assert_eq!(err, ContactError::Singular);
        assert!(err.to_string().contains("not positive definite"));
    }

    #[test]
    fn matches_brute_force_enumeration() {
        let n = 8;
        let c = compliance(n);
        for case in 0..20 {
            let g0 = DVector::from_fn(n, |k, _| {
                1e-7 * ((k * 7 + case * 3) % 5) as f64 * (1.0 + 0.1 * case as f64)
            });
            let a = DVector::from_fn(n, |k, _| 0.05 + 0.001 * k as f64);
            let torque = 50.0 + 10.0 * case as f64;
            let mut f = DVector::zeros(n);
            let sol = solve_contact(&c, &g0, &a, torque, &mut f).unwrap();
            assert!(sol.kkt_residual < 1e-9, "case {case}: {}", sol.kkt_residual);
            let mut found = false;
            for mask in 1u32..(1 << n) {
                let set: Vec<usize> = (0..n).filter(|k| mask & (1 << k) != 0).collect();
                let m = set.len();
                let mut kkt = DMatrix::zeros(m + 1, m + 1);
                let mut rhs = DVector::zeros(m + 1);
                for (i, &p) in set.iter().enumerate() {
                    for (j, &q) in set.iter().enumerate() {
                        kkt[(i, j)] = c[(p, q)];
                    }
                    kkt[(i, m)] = -a[p];
                    kkt[(m, i)] = a[p];
                    rhs[i] = -g0[p];
                }
                rhs[m] = torque;
                let Some(x) = kkt.lu().solve(&rhs) else {
                    continue;
                };
                let mut trial = DVector::zeros(n);
                for (i, &p) in set.iter().enumerate() {
                    trial[p] = x[i];
                }
                if kkt_residual(&c, &g0, &a, torque, &trial, x[m]) < 1e-9 {
                    assert!(
                        (&trial - &f).amax() < 1e-6 * f.amax(),
                        "case {case}: {trial} vs {f}"
                    );
                    assert!((x[m] - sol.rotation).abs() < 1e-9 * sol.rotation.abs());
                    found = true;
                    break;
                }
            }
            assert!(found, "case {case}: brute force found no solution");
        }
    }
}
