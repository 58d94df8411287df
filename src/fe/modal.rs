//! The lowest modes of K φ = ω² M φ (K, M sparse symmetric, M positive definite, K positive
//! semi-definite) by shift-invert Lanczos with full reorthogonalization.
//!
//! # Method (Ericsson & Ruhe 1980; Grimes, Lewis & Simon 1994)
//! With a shift σ below the lowest eigenvalue, K − σM is positive definite (also when K has
//! rigid-body modes) and is factorized once (sparse Cholesky, faer). The operator
//! ```text
//! A = (K − σM)⁻¹ M,     A φ = θ φ,     θ = 1 / (ω² − σ)
//! ```
//! is self-adjoint in the M inner product ⟨x, y⟩ = xᵀMy, and its largest θ are the lowest ω².
//! Lanczos in that inner product builds an M-orthonormal basis Q and the tridiagonal
//! T = QᵀM A Q; each eigenpair (θ, s) of T gives ω² = σ + 1/θ and φ = Q s. Every new vector is
//! M-orthogonalized against all previous ones twice (classical Gram–Schmidt, "twice is enough"),
//! so no spurious copies appear. A Ritz pair is accepted when its residual
//! ‖A φ − θ φ‖_M = |β_m s_m| is below `tolerance`·θ; the basis grows until the `count` lowest
//! pairs are accepted.
//!
//! Limit: a single-vector Lanczos finds one vector per distinct eigenvalue its start vector
//! reaches; of a cluster of (nearly) equal eigenvalues — the bending modes of identical teeth —
//! it may list fewer members than there are, and a residual test cannot tell. An isolated mode
//! (the mesh mode of a gear pair) and the lowest member of a cluster are found reliably.

use nalgebra::{DMatrix, SymmetricEigen};

use super::assembly::{symmetric_product, FactorizedStiffness, FeError};

/// One mode: ω² [rad²/s²], the frequency [Hz], the M-normalized shape (φᵀMφ = 1) and the
/// relative Lanczos residual of θ.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    pub eigenvalue: f64,
    pub frequency_hz: f64,
    pub shape: Vec<f64>,
    pub residual: f64,
}

/// Relative residual below which a Ritz pair is a mode.
pub const LANCZOS_TOLERANCE: f64 = 1e-9;

/// Σ a_k b_k in eight lanes: eight sums that do not wait on each other, in a fixed order
/// (the same bits on every vector unit).
#[inline(always)]
pub fn lane_dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..8 {
            lanes[l] += x[l] * y[l];
        }
    }
    for (l, (x, y)) in ra.iter().zip(rb).enumerate() {
        lanes[l] += x * y;
    }
    lanes.iter().sum()
}

/// The `count` lowest modes of K φ = ω² M φ, K and M given as lower-triangle triplets of
/// dimension `n`, shift σ < the lowest ω² (e.g. a negative number for a K with rigid-body
/// modes).
pub fn lowest_modes(
    n: usize,
    stiffness: &[(usize, usize, f64)],
    mass: &[(usize, usize, f64)],
    count: usize,
    shift: f64,
) -> Result<Vec<Mode>, FeError> {
    lowest_modes_within(
        n,
        stiffness,
        mass,
        count,
        shift,
        (LANCZOS_TOLERANCE, f64::INFINITY),
    )
}

/// [`lowest_modes`] with the modes of ω² up to `ceiling` converged to the relative residual
/// `tolerance` (`(tolerance, ceiling)`). With a finite ceiling it returns every mode up to the
/// ceiling and the first above it (at least `count` modes), each converged: the Krylov space
/// starts at 1.5 `count` + 20 vectors and grows by a quarter (at least 20) until they are, so
/// that it holds about what they need and not what a guessed count would (the
/// reorthogonalization's cost grows with its square; on the paper's driver block at 267 kHz,
/// 284 modes, a count from Weyl's law built 860 vectors in 12.7 s). Returning the first mode
/// above the ceiling converged is what shows the space reached past it: shift-invert Lanczos
/// converges from the shift outwards, so a mode below it missed would lie between converged
/// Ritz values, which does not happen short of a start vector without it (as for any Lanczos).
/// Tolerance 1e-4 serves a reduction basis, whose subspace below its cutoff matters and not
/// each vector (a cluster of near-equal modes, as a gear's teeth have, converges as a subspace
/// long before its vectors do). With an infinite ceiling the `count` lowest, the space from
/// 2 `count` + 20 vectors, doubling.
pub fn lowest_modes_within(
    n: usize,
    stiffness: &[(usize, usize, f64)],
    mass: &[(usize, usize, f64)],
    count: usize,
    shift: f64,
    (tolerance, ceiling): (f64, f64),
) -> Result<Vec<Mode>, FeError> {
    let count = count.min(n);
    let shifted: Vec<(usize, usize, f64)> = stiffness
        .iter()
        .copied()
        .chain(mass.iter().map(|&(r, c, v)| (r, c, -shift * v)))
        .collect();
    let factor = FactorizedStiffness::new(n, shifted, &[])?;
    let dot = lane_dot;

    // A deterministic start vector with every component present.
    let start: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * ((i as f64) * 0.618_033_988_7).fract())
        .collect();
    let m_start = symmetric_product(mass, &start);
    let norm = dot(&start, &m_start).sqrt();
    let mut basis: Vec<Vec<f64>> = vec![start.iter().map(|x| x / norm).collect()];
    let mut m_basis: Vec<Vec<f64>> = vec![m_start.iter().map(|x| x / norm).collect()];
    let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut target = if ceiling.is_finite() {
        count + count / 2 + 20
    } else {
        2 * count + 20
    }
    .min(n);
    // The Krylov space holds every mode the start vector reaches (invariant, or all of n).
    let mut exhausted = false;
    loop {
        while alpha.len() < target {
            let j = alpha.len();
            let mut w = factor.solve(&m_basis[j]);
            let a = dot(&m_basis[j], &w);
            alpha.push(a);
            for _pass in 0..2 {
                for (q, mq) in basis.iter().zip(&m_basis) {
                    let c = dot(mq, &w);
                    w.iter_mut().zip(q).for_each(|(wi, qi)| *wi -= c * qi);
                }
            }
            let mw = symmetric_product(mass, &w);
            let b = dot(&w, &mw).max(0.0).sqrt();
            beta.push(b);
            // An invariant subspace: every mode the start vector holds is found.
            if !(b > 1e-14 * a.abs()) || alpha.len() == n {
                exhausted = true;
                break;
            }
            basis.push(w.iter().map(|x| x / b).collect());
            m_basis.push(mw.iter().map(|x| x / b).collect());
        }
        let m = alpha.len();
        let t = DMatrix::from_fn(m, m, |i, j| match i.abs_diff(j) {
            0 => alpha[i],
            1 => beta[i.min(j)],
            _ => 0.0,
        });
        let eigen = SymmetricEigen::new(t);
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let last_beta = beta[m - 1];
        let residual = |k: usize| {
            (last_beta * eigen.eigenvectors[(m - 1, k)]).abs() / eigen.eigenvalues[k].abs()
        };
        // θ = 1/(ω² − σ): the modes up to the ceiling are those of θ at or above its θ.
        let ceiling_theta = 1.0 / (ceiling - shift);
        let (wanted, converged) = if ceiling.is_finite() {
            // Every Ritz pair below the ceiling and the first above it converged: the space
            // has then reached past the ceiling (shift-invert converges from the shift
            // outwards), and no more is built than that needs.
            let below = order
                .iter()
                .take_while(|&&k| eigen.eigenvalues[k] >= ceiling_theta)
                .count();
            let wanted = &order[..(below + 1).max(count).min(m)];
            let converged = below < m && wanted.iter().all(|&k| residual(k) < tolerance);
            (wanted, converged)
        } else {
            let wanted = &order[..count.min(m)];
            (wanted, wanted.iter().all(|&k| residual(k) < tolerance))
        };
        if converged || exhausted {
            // The shapes Q S at once (a matrix product over the basis, not one pass over it
            // per mode: with hundreds of modes those passes were a sixth of a block's build).
            let q = DMatrix::from_fn(n, m, |r, i| basis[i][r]);
            let s = DMatrix::from_fn(m, wanted.len(), |i, c| eigen.eigenvectors[(i, wanted[c])]);
            let shapes = q * s;
            let modes = wanted
                .iter()
                .zip(shapes.column_iter())
                .map(|(&k, shape)| {
                    let theta = eigen.eigenvalues[k];
                    let eigenvalue = shift + 1.0 / theta;
                    Mode {
                        eigenvalue,
                        frequency_hz: eigenvalue.max(0.0).sqrt() / std::f64::consts::TAU,
                        shape: shape.as_slice().to_vec(),
                        residual: residual(k),
                    }
                })
                .collect();
            return Ok(modes);
        }
        target = if ceiling.is_finite() {
            m + (m / 4).max(20)
        } else {
            2 * m
        }
        .min(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed–free chain of n equal masses and springs: ω_k = 2√(k/m) sin((2k−1)π/(2(2n+1))).
    #[test]
    fn spring_chain_matches_the_analytic_frequencies() {
        let (n, k, m) = (300, 2.0e6, 0.3);
        let (stiffness, mass) = fixed_free_chain(n, k, m);
        let modes = lowest_modes(n, &stiffness, &mass, 8, -1.0).unwrap();
        for (j, mode) in modes.iter().enumerate() {
            let exact = chain_frequency(n, k, m, j);
            let omega = mode.eigenvalue.sqrt();
            assert!(
                (omega / exact - 1.0).abs() < 1e-9,
                "mode {j}: {omega} vs {exact}"
            );
            let mphi = symmetric_product(&mass, &mode.shape);
            let norm: f64 = mode.shape.iter().zip(&mphi).map(|(a, b)| a * b).sum();
            assert!((norm - 1.0).abs() < 1e-9);
        }
    }

    type Triplets = Vec<(usize, usize, f64)>;

    /// A fixed–free chain of `n` masses `m` and springs `k`: K and M as lower triplets.
    fn fixed_free_chain(n: usize, k: f64, m: f64) -> (Triplets, Triplets) {
        let mut stiffness = Vec::new();
        for i in 0..n {
            // Spring i joins mass i−1 (the wall for i = 0) and mass i.
            stiffness.push((i, i, if i + 1 < n { 2.0 * k } else { k }));
            if i > 0 {
                stiffness.push((i, i - 1, -k));
            }
        }
        (stiffness, (0..n).map(|i| (i, i, m)).collect())
    }

    /// ω of [`fixed_free_chain`]'s mode `j` (from 0) [rad/s].
    fn chain_frequency(n: usize, k: f64, m: f64, j: usize) -> f64 {
        2.0 * (k / m).sqrt()
            * ((2 * j + 1) as f64 * std::f64::consts::PI / (2.0 * (2 * n + 1) as f64)).sin()
    }

    /// With a ceiling, every mode below it and the first above it, each converged, whatever
    /// the count asked (4 here, 40 below the ceiling); and a ceiling above every mode of a
    /// small chain returns them all (the Krylov space exhausted before any lies above).
    #[test]
    fn a_ceiling_returns_every_mode_below_it_and_the_first_above() {
        let (n, k, m) = (300, 2.0e6, 0.3);
        let (stiffness, mass) = fixed_free_chain(n, k, m);
        let below = 40;
        let ceiling =
            (0.5 * (chain_frequency(n, k, m, below - 1) + chain_frequency(n, k, m, below))).powi(2);
        let modes = lowest_modes_within(n, &stiffness, &mass, 4, 0.0, (1e-8, ceiling)).unwrap();
        assert_eq!(modes.len(), below + 1);
        for (j, mode) in modes.iter().enumerate() {
            let exact = chain_frequency(n, k, m, j);
            assert!(
                (mode.eigenvalue.sqrt() / exact - 1.0).abs() < 1e-9,
                "mode {j}"
            );
            assert!(mode.residual < 1e-8, "mode {j}: residual {}", mode.residual);
        }
        assert!(modes[below].eigenvalue > ceiling && modes[below - 1].eigenvalue < ceiling);

        let small = 10;
        let (stiffness, mass) = fixed_free_chain(small, k, m);
        let all = lowest_modes_within(small, &stiffness, &mass, 4, 0.0, (1e-8, 1e12)).unwrap();
        assert_eq!(all.len(), small);
        for (j, mode) in all.iter().enumerate() {
            let exact = chain_frequency(small, k, m, j);
            assert!(
                (mode.eigenvalue.sqrt() / exact - 1.0).abs() < 1e-9,
                "mode {j}"
            );
        }
    }

    /// A free–free chain with a consistent (tridiagonal) mass: the rigid mode at 0 below a
    /// negative shift, the rest against the dense generalized eigenproblem.
    #[test]
    fn free_chain_with_consistent_mass_matches_the_dense_solution() {
        let n = 60;
        let (k, m) = (1.0e5, 0.2);
        let mut kd = DMatrix::<f64>::zeros(n, n);
        let mut md = DMatrix::<f64>::zeros(n, n);
        for e in 0..n - 1 {
            let (a, b) = (e, e + 1);
            kd[(a, a)] += k;
            kd[(b, b)] += k;
            kd[(a, b)] -= k;
            kd[(b, a)] -= k;
            md[(a, a)] += m / 3.0;
            md[(b, b)] += m / 3.0;
            md[(a, b)] += m / 6.0;
            md[(b, a)] += m / 6.0;
        }
        let lower = |d: &DMatrix<f64>| {
            let mut t = Vec::new();
            for i in 0..n {
                for j in 0..=i {
                    if d[(i, j)] != 0.0 {
                        t.push((i, j, d[(i, j)]));
                    }
                }
            }
            t
        };
        let modes = lowest_modes(n, &lower(&kd), &lower(&md), 6, -1.0e3).unwrap();
        let l = md.clone().cholesky().unwrap().l();
        let l_inv = l.clone().try_inverse().unwrap();
        let reduced = &l_inv * &kd * l_inv.transpose();
        let mut exact: Vec<f64> = SymmetricEigen::new(reduced)
            .eigenvalues
            .iter()
            .copied()
            .collect();
        exact.sort_by(f64::total_cmp);
        assert!(
            modes[0].eigenvalue.abs() < 1e-6 * exact[1],
            "rigid mode {}",
            modes[0].eigenvalue
        );
        for j in 1..6 {
            assert!(
                (modes[j].eigenvalue / exact[j] - 1.0).abs() < 1e-9,
                "mode {j}: {} vs {}",
                modes[j].eigenvalue,
                exact[j]
            );
        }
    }
}
