//! Penalty contact with regularized Coulomb friction for the explicit solver: the projection of a
//! point (a slave node or Gauss point) on a quadratic (Q8) edge and the normal/tangential force
//! law. The pair's contact search and assembly are in [`crate::explicit::pair`].
//!
//! # Geometry
//! A master edge is the quadratic curve x(s) = Σ Nᵢ(s) xᵢ, s ∈ [−1, 1], through its corner, mid-side
//! and corner nodes (N = [s(s−1)/2, 1 − s², s(s+1)/2]). A slave node p is projected by Newton's
//! method on (x(s) − p)·x′(s) = 0; the gap is g = (p − x(s))·n with n the unit normal on the
//! outside of the master body (the edge runs counter-clockwise around it, so n = (t_y, −t_x)).
//!
//! # Force law (per slave node, penalty regularization as in LS-DYNA's default contact)
//! ```text
//! normal      F_n = k_n · max(−g, 0)                               (no tension)
//! tangential  F_t,trial = F_t,old − k_t Δu_t                       (elastic stick spring)
//!             F_t = F_t,trial                 if |F_t,trial| ≤ μ F_n   (stick)
//!             F_t = μ F_n sign(F_t,trial)     otherwise                 (slip: Coulomb)
//! ```
//! Δu_t is the relative tangential displacement of the slave over the master in the step. The
//! return mapping makes the friction force exactly μ F_n while sliding and bounded by it while
//! sticking; the stick spring k_t sets the (small) elastic creep before sliding.

use nalgebra::{Point2, Vector2};

/// Closest point of a quadratic edge to a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Edge parameter s ∈ [−1, 1].
    pub parameter: f64,
    pub point: Point2<f64>,
    /// Unit tangent along the edge (direction of increasing s).
    pub tangent: Vector2<f64>,
    /// Unit normal pointing out of the master body.
    pub normal: Vector2<f64>,
    /// Signed gap (p − x(s))·n: positive apart, negative penetrating.
    pub gap: f64,
    /// Shape-function weights of the three edge nodes at s, for distributing the reaction.
    pub weights: [f64; 3],
}

/// Projects `p` on the quadratic edge through `nodes` (corner, mid-side, corner).
pub fn project_on_quadratic_edge(p: &Point2<f64>, nodes: &[Point2<f64>; 3]) -> Projection {
    let [a, m, b] = nodes.map(|q| q.coords);
    let position =
        |s: f64| a * (0.5 * s * (s - 1.0)) + m * (1.0 - s * s) + b * (0.5 * s * (s + 1.0));
    let first = |s: f64| a * (s - 0.5) - m * (2.0 * s) + b * (s + 0.5);
    let second = a - m * 2.0 + b;
    // Start from the chord projection, then Newton on f(s) = (x(s) − p)·x′(s).
    let chord = b - a;
    let mut s = (2.0 * (p.coords - a).dot(&chord) / chord.norm_squared() - 1.0).clamp(-1.0, 1.0);
    for _ in 0..20 {
        let (x, d1) = (position(s), first(s));
        let f = (x - p.coords).dot(&d1);
        let df = d1.norm_squared() + (x - p.coords).dot(&second);
        if df.abs() < 1e-300 {
            break;
        }
        let next = (s - f / df).clamp(-1.0, 1.0);
        if (next - s).abs() < 1e-14 {
            s = next;
            break;
        }
        s = next;
    }
    let tangent = first(s).normalize();
    let normal = Vector2::new(tangent.y, -tangent.x);
    let point = Point2::from(position(s));
    Projection {
        parameter: s,
        point,
        tangent,
        normal,
        gap: (p - point).dot(&normal),
        weights: [0.5 * s * (s - 1.0), 1.0 - s * s, 0.5 * s * (s + 1.0)],
    }
}

/// Penalty and friction parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    /// Normal penalty stiffness k_n [N/m].
    pub normal_stiffness: f64,
    /// Tangential (stick) penalty stiffness k_t [N/m].
    pub tangential_stiffness: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
}

/// The friction history of one slave node.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionState {
    /// Tangential force carried by the stick spring [N].
    pub tangential_force: f64,
    /// Whether the node slid in its last update.
    pub sliding: bool,
}

impl ContactLaw {
    /// Normal and tangential force magnitudes on the slave for gap `gap` and tangential slip
    /// increment `slip` over the step (along the master tangent); updates the friction history.
    /// The tangential force acts along the master tangent, opposing the accumulated slip.
    pub fn forces(&self, gap: f64, slip: f64, state: &mut FrictionState) -> (f64, f64) {
        let normal = self.normal_stiffness * (-gap).max(0.0);
        if normal == 0.0 {
            *state = FrictionState::default();
            return (0.0, 0.0);
        }
        let trial = state.tangential_force - self.tangential_stiffness * slip;
        let limit = self.friction * normal;
        let (tangential, sliding) = if trial.abs() <= limit {
            (trial, false)
        } else {
            (limit * trial.signum(), true)
        };
        *state = FrictionState {
            tangential_force: tangential,
            sliding,
        };
        (normal, tangential)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a quadratic edge through three points of a circle (a good approximation of the arc),
    /// the projection of an outside point lands on the radial line through it, and the gap is its
    /// distance from the circle to O(h⁴).
    #[test]
    fn projection_on_a_curved_edge() {
        let radius = 0.05;
        // The edge runs counter-clockwise around the disc (increasing angle), as the outline does.
        let angles = [0.1_f64, 0.2, 0.3];
        let nodes = angles.map(|t| Point2::new(radius * t.cos(), radius * t.sin()));
        let p = Point2::new(0.051 * 0.22_f64.cos(), 0.051 * 0.22_f64.sin());
        let proj = project_on_quadratic_edge(&p, &nodes);
        let angle = proj.point.y.atan2(proj.point.x);
        assert!((angle - 0.22).abs() < 1e-4, "angle {angle}");
        assert!((proj.gap - 0.001).abs() < 1e-6, "gap {}", proj.gap);
        assert!((proj.weights.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(
            proj.normal.dot(&proj.point.coords) > 0.0,
            "normal points out of the disc"
        );
    }

    /// A block of mass m pressed on a rigid floor with N and pulled by a tangential force T(t) =
    /// ramp: it sticks (friction = T) until T reaches μN, then slides with friction μN and
    /// acceleration (T − μN)/m. Integrated with the explicit central difference; compared with
    /// the Coulomb solution.
    #[test]
    fn sliding_block_follows_coulomb_stick_and_slip() {
        let (m, normal_load, mu) = (2.0, 1000.0, 0.15);
        let law = ContactLaw {
            normal_stiffness: 1e9,
            tangential_stiffness: 1e8,
            friction: mu,
        };
        let ramp = 4000.0; // N/s
        let pull = |t: f64| ramp * t;
        let dt = 1e-6; // well below 2/√(k/m) = 2.8e-4 s
        let (mut x, mut v) = (0.0_f64, 0.0_f64);
        let mut state = FrictionState::default();
        // The floor carries the normal load through the penalty: static gap −N/k_n.
        let gap = -normal_load / law.normal_stiffness;
        let mut slip_started = None;
        let mut t = 0.0;
        let mut previous_x = 0.0;
        while t < 0.1 {
            let (f_n, f_t) = law.forces(gap, x - previous_x, &mut state);
            assert!((f_n - normal_load).abs() < 1e-6);
            previous_x = x;
            let a = (pull(t) + f_t) / m;
            v += a * dt;
            x += v * dt;
            t += dt;
            if state.sliding && slip_started.is_none() {
                slip_started = Some(t);
            }
            if slip_started.is_none() {
                // Stick: the block rides the stick spring only: undamped ramp response
                // x = (ramp/k_t)(t − sin(ωt)/ω) ≤ (ramp/k_t)(t + 1/ω).
                let omega = (law.tangential_stiffness / m).sqrt();
                let bound = ramp / law.tangential_stiffness * (t + 1.0 / omega);
                assert!(
                    x.abs() <= 1.01 * bound,
                    "creep {x} at t = {t}, bound {bound}"
                );
            } else {
                // Slip: the friction force is exactly μN against the motion.
                assert!((f_t.abs() - mu * normal_load).abs() < 1e-9 * normal_load);
            }
        }
        let onset = slip_started.expect("the block slides");
        let expected_onset = mu * normal_load / ramp;
        // The stick spring's oscillation (amplitude ramp/(k_t ω) in force-time) shifts the onset by
        // at most 1/ω: the regularization's own time scale.
        let omega = (law.tangential_stiffness / m).sqrt();
        assert!(
            (onset - expected_onset).abs() <= 1.0 / omega + dt,
            "slip at {onset} vs {expected_onset}"
        );
        // After the onset: x'' = (ramp t − μN)/m → v(t) = ramp (t − t₀)²/(2m).
        let expected_v = ramp * (t - expected_onset).powi(2) / (2.0 * m);
        assert!(
            (v - expected_v).abs() < 1e-2 * expected_v,
            "v {v} vs {expected_v}"
        );
    }
}
