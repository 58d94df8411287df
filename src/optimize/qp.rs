//! A small dense convex quadratic program solved by Clarabel (Goulart & Chen 2024, an
//! interior-point method on a homogeneous embedding that takes the quadratic objective
//! directly):
//! ```text
//! minimize ½ xᵀP x + qᵀx    subject to    A x = b,    G x ≤ h,    P ⪰ 0
//! ```
//! Clarabel's form is A' x + s = b', s ∈ K with K = {0}ᵐ × ℝ₊ᵖ, so the rows are [A; G] and
//! [b; h]. The solution is checked here, not only by the solver's status: the KKT residual
//! max(‖Px + q + Aᵀy + Gᵀz‖∞ / scale, primal infeasibility, |zᵢ(h − Gx)ᵢ| / scale, dual
//! infeasibility z⁻) is returned with it.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use nalgebra::{DMatrix, DVector};

/// The problem; `a` and `g` may have zero rows.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadraticProgram {
    pub p: DMatrix<f64>,
    pub q: DVector<f64>,
    pub a: DMatrix<f64>,
    pub b: DVector<f64>,
    pub g: DMatrix<f64>,
    pub h: DVector<f64>,
}

/// The solution with its multipliers (y for A x = b, z ≥ 0 for G x ≤ h).
#[derive(Debug, Clone, PartialEq)]
pub struct QpSolution {
    pub x: DVector<f64>,
    pub objective: f64,
    pub y: DVector<f64>,
    pub z: DVector<f64>,
    pub kkt_residual: f64,
    pub iterations: u32,
    pub solve_s: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QpError {
    #[error("the QP is malformed: {0}")]
    Shape(String),
    #[error("the QP has no solution: Clarabel reports {0} (the constraints cannot all hold, or the objective is unbounded)")]
    NotSolved(String),
    #[error("the QP's data hold NaN or infinity (the linearization it came from is broken)")]
    NotFinite,
}

/// Column-compressed form of `m`; with `upper`, only its upper triangle (Clarabel reads P so).
fn csc(m: &DMatrix<f64>, upper: bool) -> CscMatrix<f64> {
    let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if (!upper || i <= j) && m[(i, j)] != 0.0 {
                rowval.push(i);
                nzval.push(m[(i, j)]);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(m.nrows(), m.ncols(), colptr, rowval, nzval)
}

/// Solves the QP; an infeasible or unbounded problem is an error that says so.
pub fn solve(problem: &QuadraticProgram) -> Result<QpSolution, QpError> {
    let n = problem.q.len();
    let (me, mi) = (problem.a.nrows(), problem.g.nrows());
    let shapes_ok = problem.p.shape() == (n, n)
        && (me == 0 || problem.a.ncols() == n)
        && (mi == 0 || problem.g.ncols() == n)
        && problem.b.len() == me
        && problem.h.len() == mi;
    if !shapes_ok {
        return Err(QpError::Shape(format!(
            "{n} variables, P {:?}, A {:?}, b {}, G {:?}, h {}",
            problem.p.shape(),
            problem.a.shape(),
            problem.b.len(),
            problem.g.shape(),
            problem.h.len()
        )));
    }
    let data = [
        problem.p.as_slice(),
        problem.q.as_slice(),
        problem.a.as_slice(),
        problem.b.as_slice(),
        problem.g.as_slice(),
        problem.h.as_slice(),
    ];
    if !data.iter().all(|d| d.iter().all(|x| x.is_finite())) {
        return Err(QpError::NotFinite);
    }
    let rows = DMatrix::from_fn(me + mi, n, |i, j| {
        if i < me {
            problem.a[(i, j)]
        } else {
            problem.g[(i - me, j)]
        }
    });
    let rhs: Vec<f64> = problem.b.iter().chain(problem.h.iter()).copied().collect();
    let mut cones = Vec::new();
    if me > 0 {
        cones.push(ZeroConeT(me));
    }
    if mi > 0 {
        cones.push(NonnegativeConeT(mi));
    }
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-10)
        .tol_gap_rel(1e-10)
        .tol_feas(1e-10)
        .build()
        .map_err(|e| QpError::Shape(format!("{e:?}")))?;
    let q: Vec<f64> = problem.q.iter().copied().collect();
    let mut solver = DefaultSolver::new(
        &csc(&problem.p, true),
        &q,
        &csc(&rows, false),
        &rhs,
        &cones,
        settings,
    )
    .map_err(|e| QpError::Shape(format!("{e:?}")))?;
    solver.solve();
    let solution = &solver.solution;
    if !matches!(
        solution.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    ) {
        return Err(QpError::NotSolved(format!("{:?}", solution.status)));
    }
    let x = DVector::from_column_slice(&solution.x);
    let y = DVector::from_iterator(me, solution.z[..me].iter().copied());
    let z = DVector::from_iterator(mi, solution.z[me..].iter().copied());
    let objective = 0.5 * x.dot(&(&problem.p * &x)) + problem.q.dot(&x);
    Ok(QpSolution {
        kkt_residual: kkt_residual(problem, &x, &y, &z),
        objective,
        x,
        y,
        z,
        iterations: solution.iterations,
        solve_s: solution.solve_time,
    })
}

/// The KKT residual of (x, y, z), relative to the problem's scale.
pub fn kkt_residual(
    problem: &QuadraticProgram,
    x: &DVector<f64>,
    y: &DVector<f64>,
    z: &DVector<f64>,
) -> f64 {
    let mut gradient = &problem.p * x + &problem.q;
    if !y.is_empty() {
        gradient += problem.a.transpose() * y;
    }
    if !z.is_empty() {
        gradient += problem.g.transpose() * z;
    }
    let scale = 1.0 + problem.q.amax() + (&problem.p * x).amax();
    let slack = if !z.is_empty() {
        &problem.h - &problem.g * x
    } else {
        DVector::zeros(0)
    };
    let equality = if !y.is_empty() {
        (&problem.a * x - &problem.b).amax()
    } else {
        0.0
    };
    let x_scale = 1.0 + x.amax();
    let primal = slack.iter().map(|s| (-s).max(0.0)).fold(equality, f64::max) / x_scale;
    let dual = z.iter().map(|v| (-v).max(0.0)).fold(0.0, f64::max) / scale;
    let complementarity = slack
        .iter()
        .zip(z.iter())
        .map(|(s, v)| (s * v).abs())
        .fold(0.0, f64::max)
        / (scale * x_scale);
    (gradient.amax() / scale)
        .max(primal)
        .max(dual)
        .max(complementarity)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// minimize 3x₁² + 2x₂² − x₁ − 4x₂ with x₁ = 2x₂ and −1 ≤ x ≤ u: on the line,
    /// 14x₂² − 6x₂, so x₂ = 3/14 while the box allows it, else the bound.
    fn problem(upper: f64) -> QuadraticProgram {
        QuadraticProgram {
            p: DMatrix::from_row_slice(2, 2, &[6.0, 0.0, 0.0, 4.0]),
            q: DVector::from_row_slice(&[-1.0, -4.0]),
            a: DMatrix::from_row_slice(1, 2, &[1.0, -2.0]),
            b: DVector::from_row_slice(&[0.0]),
            g: DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, -1.0]),
            h: DVector::from_row_slice(&[upper, upper, 1.0, 1.0]),
        }
    }

    #[test]
    fn known_optima_with_and_without_an_active_bound() {
        let free = solve(&problem(1.0)).unwrap();
        assert!((free.x[1] - 3.0 / 14.0).abs() < 1e-8 && (free.x[0] - 3.0 / 7.0).abs() < 1e-8);
        assert!((free.objective + 9.0 / 14.0).abs() < 1e-8);
        assert!(free.kkt_residual < 1e-8, "{}", free.kkt_residual);
        // x₁ ≤ 0.1 binds: x = (0.1, 0.05), its multiplier z₁ > 0 and the others 0.
        let bound = solve(&problem(0.1)).unwrap();
        assert!((bound.x[0] - 0.1).abs() < 1e-8 && (bound.x[1] - 0.05).abs() < 1e-8);
        assert!(bound.z[0] > 1e-3 && bound.z.iter().skip(1).all(|v| v.abs() < 1e-6));
        assert!(bound.kkt_residual < 1e-8, "{}", bound.kkt_residual);
        // A wrong multiplier shows in the residual.
        let mut z = bound.z.clone();
        z[0] *= 1.5;
        assert!(kkt_residual(&problem(0.1), &bound.x, &bound.y, &z) > 1e-2);
    }

    #[test]
    fn infeasible_and_malformed_problems_are_errors() {
        // x₁ ≤ −2 against x₁ ≥ −1.
        let mut p = problem(1.0);
        p.h[0] = -2.0;
        assert!(matches!(solve(&p), Err(QpError::NotSolved(_))));
        p.h = DVector::zeros(3);
        assert!(matches!(solve(&p), Err(QpError::Shape(_))));
        let mut p = problem(1.0);
        p.q[0] = f64::NAN;
        assert!(matches!(solve(&p), Err(QpError::NotFinite)));
    }
}
