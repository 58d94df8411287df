//! The load-dependent mesh force law W(θ, δ) of one set of flanks: the quasi-static mesh force
//! along the line of action as a function of the driver roll angle θ and the approach δ (the
//! transmission error along the line of action), tabulated by the LTCA from first contact up
//! to several times the design load.
//!
//! A secant k(θ) taken at one torque ([`super::MeshStiffness`]) gives W = k(θ)(δ − e(θ)): right
//! at that torque only. A real pair stiffens with load (more contact points close on the curved
//! flanks, relieved tips come into contact, the loaded contact ratio grows), so its quasi-static
//! answer at another torque is not the secant's. The table holds the LTCA's own answers.
//!
//! # Table and interpolation
//! At each position j of a uniform grid over one mesh period the LTCA gives, for torques T_k,
//! the approach δ_jk = r_b2 φ_jk, the mesh force W_jk = T_k / r_b2 (the force the 1-DOF model
//! balances; Σ F equals it where the normals lie on the line of action) and the tangent stiffness
//! m_jk = dW/dδ = aᵀC_AA⁻¹a / r_b2² on the active set; the first knot is first contact,
//! δ_j0 = e(θ_j) (the unloaded TE, r_b2 φ₀), W_j0 = 0. Between knots W_j(δ) is the cubic
//! Hermite interpolant (C¹ in δ, as RK4 and the linearizations need) with slopes limited to
//! three times the adjacent secants, the Fritsch–Carlson condition that keeps it monotone
//! (Fritsch & Carlson 1980, *SIAM J. Numer. Anal.* 17(2)); the first knot's slope is the
//! quadratic end condition 2Δ₀ − m₁ clipped to [0, 3Δ₀]. Below first contact W = 0; above the
//! last knot W continues with the last tangent. Between positions W(θ, δ) = (1 − t) W_j(δ) +
//! t W_{j+1}(δ), periodic over the mesh period, so W stays monotone in δ.

use crate::geometry::GearPair;
use crate::ltca::PositionResult;

/// One knot of a position's force law: approach δ [m], force W [N], slope dW/dδ [N/m].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knot {
    pub deflection: f64,
    pub force: f64,
    pub slope: f64,
}

/// The mesh force law W(θ, δ) of one set of flanks over one mesh period (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct ForceLaw {
    /// Where it comes from, for outputs.
    pub source: String,
    /// Period in driver roll angle [rad].
    pub period: f64,
    /// Driver roll angle of the first position [rad] (θ = 0 of [`ForceLaw::force`]).
    pub origin: f64,
    /// Load torques on the driven gear the knots were solved at [N·m], ascending.
    pub torques: Vec<f64>,
    /// Knots of each position (uniform over one period), first contact first.
    pub knots: Vec<Vec<Knot>>,
}

impl ForceLaw {
    /// The law from the LTCA's cycles at ascending `torques` (`cycles[k][j]`: torque k,
    /// position j, the positions uniform over one base pitch). Errors say what is wrong.
    pub fn from_ltca(
        pair: &GearPair,
        torques: &[f64],
        cycles: &[Vec<PositionResult>],
        source: impl Into<String>,
    ) -> Result<Self, String> {
        if torques.is_empty() || torques.len() != cycles.len() {
            return Err(format!(
                "{} torques and {} LTCA cycles: give one cycle per torque, at least one",
                torques.len(),
                cycles.len()
            ));
        }
        if torques.windows(2).any(|w| !(w[1] > w[0])) || !(torques[0] > 0.0) {
            return Err("the force law's torques must be positive and ascending".into());
        }
        let positions = cycles[0].len();
        if positions == 0 || cycles.iter().any(|c| c.len() != positions) {
            return Err("every LTCA cycle of the force law needs the same positions".into());
        }
        let rb2 = pair.gears[1].base_radius;
        let mut knots = Vec::with_capacity(positions);
        for j in 0..positions {
            let first = &cycles[0][j];
            let mut position = vec![Knot {
                deflection: rb2 * first.unloaded_te,
                force: 0.0,
                slope: f64::NAN,
            }];
            for (cycle, torque) in cycles.iter().zip(torques) {
                let r = &cycle[j];
                // The 1-DOF mesh force is the torque over the base radius (what the lumped
                // model balances); ΣF differs from it where relief turns the normals off the
                // line of action. The tangent stiffness is d(T/r_b2)/dδ already.
                let knot = Knot {
                    deflection: rb2 * r.ste,
                    force: torque / rb2,
                    slope: r.tangent_stiffness,
                };
                let last = position.last().expect("first contact");
                if !(knot.deflection > last.deflection && knot.force > last.force) {
                    return Err(format!(
                        "the LTCA's approach does not grow with the load at position {j} \
                         (torque {torque:.4} N·m: δ {:.6e} m after {:.6e} m): the force law \
                         needs a monotone load-deflection curve",
                        knot.deflection, last.deflection
                    ));
                }
                position.push(knot);
            }
            limit_slopes(&mut position);
            knots.push(position);
        }
        Ok(Self {
            source: source.into(),
            period: pair.gears[0].angular_pitch(),
            origin: cycles[0][0].roll_angle,
            torques: torques.to_vec(),
            knots,
        })
    }

    /// The law with a compliance `c` [m/N] taken out of series: each knot's approach less c W,
    /// its slope 1/(1/m − c). `None` when c is not below every knot's 1/m (the rest would not
    /// be a stiffness).
    pub fn without_series_compliance(&self, c: f64) -> Option<Self> {
        let mut out = self.with_series_compliances(|_| -c)?;
        out.source = format!("{} without {c:.3e} m/N body twist", self.source);
        Some(out)
    }

    /// The law whose secant at mesh force `force` [N] is `target(θ)` [N/m] at each of its
    /// positions θ (measured from [`ForceLaw::origin`]): each position gets the series
    /// compliance c_j = 1/k_target(θ_j) − 1/k_j (k_j its own secant W/(δ − e) at `force`),
    /// δ → δ + c_j W, so first contact stays and the load dependence keeps its shape about the
    /// new secant. This carries another model's k(θ) at one load (the explicit FE's, from its
    /// low-speed DTE) with the LTCA's stiffening around it (c_j < 0 where the target is the
    /// stiffer). `None` where a target is not positive and finite, or where a knot's
    /// 1/m + c_j is not positive or the approaches would stop growing (a target far stiffer
    /// than the law at its highest loads).
    pub fn with_secant_at(&self, force: f64, target: impl Fn(f64) -> f64) -> Option<Self> {
        let n = self.knots.len();
        let own = self.secant_stiffness(force, n);
        let compliances: Vec<f64> = (0..n)
            .map(|j| {
                let k = target(j as f64 * self.period / n as f64);
                (k > 0.0 && k.is_finite() && own[j] > 0.0).then(|| 1.0 / k - 1.0 / own[j])
            })
            .collect::<Option<_>>()?;
        self.with_series_compliances(|j| compliances[j])
    }

    /// The law with compliance `c(j)` [m/N] added in series at position j: each knot's approach
    /// plus c W, its slope 1/(1/m + c). `None` when a knot's 1/m + c is not positive or the
    /// approaches would stop growing.
    fn with_series_compliances(&self, c: impl Fn(usize) -> f64) -> Option<Self> {
        let mut out = self.clone();
        for (j, position) in out.knots.iter_mut().enumerate() {
            let c = c(j);
            for knot in position.iter_mut() {
                knot.deflection += c * knot.force;
                if knot.slope > 0.0 {
                    let rest = 1.0 / knot.slope + c;
                    if !(rest > 0.0) {
                        return None;
                    }
                    knot.slope = 1.0 / rest;
                }
            }
            if position
                .windows(2)
                .any(|w| !(w[1].deflection > w[0].deflection))
            {
                return None;
            }
            limit_slopes(position);
        }
        Some(out)
    }

    /// The positions' indices and weight around θ (measured from [`ForceLaw::origin`]).
    fn bracket(&self, theta: f64) -> (usize, usize, f64) {
        let n = self.knots.len();
        // The fraction of a period without fmod or floor calls (the sweep's hot path): a
        // truncation, moved down by one period for negative angles.
        let periods = theta / self.period;
        let mut fraction = periods - periods.trunc();
        if fraction < 0.0 {
            fraction += 1.0;
        }
        let u = fraction * n as f64;
        let i = (u as usize).min(n - 1);
        (i, (i + 1) % n, u - i as f64)
    }

    /// Mesh force W(θ, δ) [N] and its slope dW/dδ [N/m] at driver roll angle θ from the origin
    /// and approach δ [m]; zero below first contact.
    pub fn force_and_slope(&self, theta: f64, deflection: f64) -> (f64, f64) {
        let (i, j, t) = self.bracket(theta);
        let (wi, si) = position_force(&self.knots[i], deflection);
        let (wj, sj) = position_force(&self.knots[j], deflection);
        (wi * (1.0 - t) + wj * t, si * (1.0 - t) + sj * t)
    }

    /// The largest slope dW/dδ of any knot [N/m]: the stiffest the law gets (between knots the
    /// Hermite slope stays within three times the secants, which the knots' slopes bound on a
    /// stiffening curve; past the last knot the law keeps its slope).
    pub fn max_slope(&self) -> f64 {
        self.knots
            .iter()
            .flatten()
            .map(|k| k.slope)
            .fold(0.0, f64::max)
    }

    /// Mesh force W(θ, δ) [N] (as [`ForceLaw::force_and_slope`], without the slope).
    pub fn force(&self, theta: f64, deflection: f64) -> f64 {
        let (i, j, t) = self.bracket(theta);
        let wi = position_force_only(&self.knots[i], deflection);
        let wj = position_force_only(&self.knots[j], deflection);
        wi * (1.0 - t) + wj * t
    }

    /// First contact, the approach where W starts to grow at θ [m] (the unloaded TE).
    pub fn first_contact(&self, theta: f64) -> f64 {
        let (i, j, t) = self.bracket(theta);
        // The blend grows as soon as either weighted position does.
        let (a, b) = (self.knots[i][0].deflection, self.knots[j][0].deflection);
        match t {
            0.0 => a,
            _ if t >= 1.0 => b,
            _ => a.min(b),
        }
    }

    /// The quasi-static approach under mesh force W > 0 at θ: the δ with W(θ, δ) = W [m]
    /// (W is monotone in δ; bisection to 1e-12 of the bracket, then a Newton step).
    pub fn deflection_under(&self, theta: f64, force: f64) -> f64 {
        let mut low = self.first_contact(theta);
        let top = |i: usize| *self.knots[i].last().expect("knots");
        let (i, j, _) = self.bracket(theta);
        let reach = top(i).deflection.max(top(j).deflection);
        let slope = top(i).slope.min(top(j).slope).max(1.0);
        // Past the last knot W grows at least with the smaller last slope.
        let mut high = reach + (force / slope).max(0.0);
        while self.force(theta, high) < force {
            high += high - low;
        }
        for _ in 0..200 {
            let mid = 0.5 * (low + high);
            if self.force(theta, mid) < force {
                low = mid;
            } else {
                high = mid;
            }
            if high - low <= 1e-12 * high.abs().max(1e-9) {
                break;
            }
        }
        let mid = 0.5 * (low + high);
        let (w, s) = self.force_and_slope(theta, mid);
        if s > 0.0 {
            (mid - (w - force) / s).clamp(low, high)
        } else {
            mid
        }
    }

    /// The secant stiffness W/(δ − e) under mesh force `force` at each of `positions` uniform
    /// positions of one period (the [`super::MeshStiffness`] this law gives at that load).
    /// At the law's own positions e is the position's first knot: θ_j = j·period/n can round
    /// into the bracket below (t ≈ 1), whose blended first contact would be the lower of two.
    pub fn secant_stiffness(&self, force: f64, positions: usize) -> Vec<f64> {
        (0..positions)
            .map(|j| {
                let theta = j as f64 * self.period / positions as f64;
                let first = match positions == self.knots.len() {
                    true => self.knots[j][0].deflection,
                    false => self.first_contact(theta),
                };
                force / (self.deflection_under(theta, force) - first)
            })
            .collect()
    }
}

/// Limits the loaded knots' slopes to three times the adjacent secants (monotone Hermite) and
/// sets the first knot's slope by the quadratic end condition.
fn limit_slopes(knots: &mut [Knot]) {
    let secant = |a: &Knot, b: &Knot| (b.force - a.force) / (b.deflection - a.deflection);
    let n = knots.len();
    let secants: Vec<f64> = knots.windows(2).map(|w| secant(&w[0], &w[1])).collect();
    for k in 1..n {
        let mut slope = knots[k].slope;
        if !(slope.is_finite() && slope > 0.0) {
            slope = secants[k - 1];
        }
        let mut bound = 3.0 * secants[k - 1];
        if k + 1 < n {
            bound = bound.min(3.0 * secants[k]);
        }
        knots[k].slope = slope.min(bound);
    }
    let next = if n > 1 { knots[1].slope } else { 0.0 };
    knots[0].slope = if n > 1 {
        (2.0 * secants[0] - next).clamp(0.0, 3.0 * secants[0])
    } else {
        0.0
    };
}

/// Where δ lies in a position's knots.
enum Segment {
    /// Below first contact: no force.
    Apart,
    /// Past the last knot: that knot's tangent.
    Beyond(Knot),
    /// Between knots a and b, h = δ_b − δ_a apart, at t = (δ − δ_a)/h.
    Within(Knot, Knot, f64, f64),
}

#[inline]
fn segment(knots: &[Knot], deflection: f64) -> Segment {
    if deflection <= knots[0].deflection {
        return Segment::Apart;
    }
    let last = *knots.last().expect("knots");
    if deflection >= last.deflection {
        return Segment::Beyond(last);
    }
    let k = knots.partition_point(|knot| knot.deflection <= deflection) - 1;
    let (a, b) = (knots[k], knots[k + 1]);
    let h = b.deflection - a.deflection;
    Segment::Within(a, b, h, (deflection - a.deflection) / h)
}

/// The cubic Hermite force between knots a and b: basis (1 − t)²(1 + 2t), t(1 − t)²,
/// t²(3 − 2t), t²(t − 1).
#[inline]
fn hermite_force(a: &Knot, b: &Knot, h: f64, t: f64) -> f64 {
    let s = 1.0 - t;
    let (h00, h10) = (s * s * (1.0 + 2.0 * t), t * s * s);
    let (h01, h11) = (t * t * (3.0 - 2.0 * t), t * t * (t - 1.0));
    h00 * a.force + h10 * h * a.slope + h01 * b.force + h11 * h * b.slope
}

/// One position's W(δ), as [`position_force`] without the slope.
#[inline]
fn position_force_only(knots: &[Knot], deflection: f64) -> f64 {
    match segment(knots, deflection) {
        Segment::Apart => 0.0,
        Segment::Beyond(last) => last.force + last.slope * (deflection - last.deflection),
        Segment::Within(a, b, h, t) => hermite_force(&a, &b, h, t),
    }
}

/// One position's W(δ) and dW/dδ: zero below first contact, cubic Hermite between knots, linear
/// past the last.
fn position_force(knots: &[Knot], deflection: f64) -> (f64, f64) {
    match segment(knots, deflection) {
        Segment::Apart => (0.0, 0.0),
        Segment::Beyond(last) => (
            last.force + last.slope * (deflection - last.deflection),
            last.slope,
        ),
        Segment::Within(a, b, h, t) => {
            let t2 = t * t;
            let d00 = (6.0 * t2 - 6.0 * t) / h;
            let d10 = 3.0 * t2 - 4.0 * t + 1.0;
            let d01 = (-6.0 * t2 + 6.0 * t) / h;
            let d11 = 3.0 * t2 - 2.0 * t;
            let slope = d00 * a.force + d10 * a.slope + d01 * b.force + d11 * b.slope;
            (hermite_force(&a, &b, h, t), slope)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn law_of(knots: Vec<Vec<Knot>>) -> ForceLaw {
        ForceLaw {
            source: "synthetic".into(),
            period: 1.0,
            origin: 0.0,
            torques: vec![],
            knots,
        }
    }

    /// Knots of W = c (δ − e)^p at `loads`, slopes exact, then limited as the LTCA's are.
    fn power_law(c: f64, p: f64, e: f64, loads: &[f64]) -> Vec<Knot> {
        let mut knots = vec![Knot {
            deflection: e,
            force: 0.0,
            slope: f64::NAN,
        }];
        for &w in loads {
            let d = (w / c).powf(1.0 / p);
            knots.push(Knot {
                deflection: e + d,
                force: w,
                slope: c * p * d.powf(p - 1.0),
            });
        }
        limit_slopes(&mut knots);
        knots
    }

    /// A linear law is reproduced exactly (Hermite with exact slopes), past the last knot too,
    /// and is zero below first contact.
    #[test]
    fn a_linear_law_is_reproduced_exactly() {
        let law = law_of(vec![power_law(2e8, 1.0, 1e-6, &[100.0, 400.0, 2000.0])]);
        for d in [0.5e-6f64, 1e-6, 1.3e-6, 3e-6, 9e-6, 30e-6] {
            let expected = (2e8 * (d - 1e-6)).max(0.0);
            let (w, s) = law.force_and_slope(0.3, d);
            assert!(
                (w - expected).abs() <= 1e-9 * 2000.0,
                "{d}: {w} vs {expected}"
            );
            let slope = if d > 1e-6 { 2e8 } else { 0.0 };
            assert!((s - slope).abs() <= 1e-6 * 2e8, "{d}: {s}");
        }
    }

    /// A stiffening law (W ∝ δ^1.3, between Hertz's 1.5 and linear) at loads a factor 1.6 apart:
    /// the interpolated approach within 0.2 % of the exact one between the knots, and the law
    /// monotone.
    #[test]
    fn a_stiffening_law_interpolates_within_its_knots() {
        let loads: Vec<f64> = (-7..=3).map(|k| 1000.0 * 1.6f64.powi(k)).collect();
        let (c, p) = (5e12, 1.3);
        let law = law_of(vec![power_law(c, p, 0.0, &loads)]);
        for w in [250.0, 500.0, 1500.0, 2000.0, 3000.0] {
            let exact = (w / c).powf(1.0 / p);
            let got = law.deflection_under(0.0, w);
            assert!((got / exact - 1.0).abs() < 2e-3, "{w}: {got} vs {exact}");
        }
        let reach = law.knots[0].last().unwrap().deflection * 1.2;
        let mut last = 0.0;
        for i in 1..2000 {
            let w = law.force(0.0, i as f64 / 2000.0 * reach);
            assert!(w >= last, "not monotone at {i}");
            last = w;
        }
    }

    /// Slopes far steeper than the secants (a contact closing just past a knot) are limited to
    /// three times the adjacent secants, so the interpolant stays monotone; without the limit the
    /// same knots give a curve that dips.
    #[test]
    fn steep_slopes_are_limited_so_the_law_stays_monotone() {
        let knot = |deflection: f64, force: f64, slope: f64| Knot {
            deflection,
            force,
            slope,
        };
        let raw = vec![
            knot(0.0, 0.0, f64::NAN),
            knot(1e-6, 100.0, 1e8),
            knot(2e-6, 110.0, 5e9),
            knot(3e-6, 500.0, 4e8),
        ];
        let dips = |knots: &[Knot]| {
            (1..3000).any(|i| {
                let d = i as f64 * 1e-9;
                position_force(knots, d).0 < position_force(knots, d - 1e-9).0 - 1e-9
            })
        };
        let mut unlimited = raw.clone();
        unlimited[0].slope = 0.0;
        assert!(dips(&unlimited), "the test's knots must need the limiter");
        let mut limited = raw;
        limit_slopes(&mut limited);
        assert!(limited[2].slope <= 3.0 * 10.0 / 1e-6 + 1e-6);
        assert!(!dips(&limited));
    }

    /// Between two positions the law blends, and the inverse solves it.
    #[test]
    fn positions_blend_and_the_inverse_solves_the_law() {
        let a = power_law(2e8, 1.0, 0.0, &[1000.0]);
        let b = power_law(4e8, 1.0, 1e-6, &[1000.0]);
        let law = law_of(vec![a, b]);
        // Half way from position 0 (θ = 0) to position 1 (θ = 0.5 of the unit period).
        let theta = 0.25;
        let d = law.deflection_under(theta, 500.0);
        let expected = 0.5 * 2e8 * d + 0.5 * 4e8 * (d - 1e-6);
        assert!((expected - 500.0).abs() < 1e-6, "{d}: {expected}");
        assert_eq!(law.first_contact(theta), 0.0);
        assert_eq!(law.force(theta, 0.0), 0.0);
        assert!(law.force(theta, 1e-9) > 0.0);
        // Periodic: one period on is the same place.
        assert_eq!(law.force(theta + 1.0, 2e-6), law.force(theta, 2e-6));
    }

    /// `force` (the fast path without the slope) is `force_and_slope`'s force to round-off
    /// everywhere: below first contact, between knots, past the last, and at angles before the
    /// origin and periods on, where the bracket folds θ into the period.
    #[test]
    fn the_force_alone_is_the_force_of_force_and_slope() {
        let loads = [50.0, 200.0, 600.0, 1500.0, 4000.0];
        let law = law_of(vec![
            power_law(3e8, 1.4, 0.0, &loads),
            power_law(5e8, 1.2, 1e-6, &loads),
            power_law(4e8, 1.3, 0.5e-6, &loads),
        ]);
        for i in -40..=40 {
            let theta = 0.0731 * i as f64;
            let period = law.period;
            // The bracket's folding against fmod's.
            let (i0, j0, t0) = law.bracket(theta);
            let u = (theta / period).rem_euclid(1.0) * 3.0;
            let k = (u.floor() as usize).min(2);
            assert_eq!((i0, j0), (k, (k + 1) % 3), "θ {theta}");
            assert!((t0 - (u - k as f64)).abs() < 1e-12, "θ {theta}");
            // Folding by whole periods changes nothing.
            assert!((law.force(theta + 3.0 * period, 4e-6) - law.force(theta, 4e-6)).abs() < 1e-9);
            for k in 0..60 {
                let d = -1e-6 + k as f64 * 0.25e-6;
                let (w, _) = law.force_and_slope(theta, d);
                let fast = law.force(theta, d);
                assert!(
                    (fast - w).abs() <= 1e-12 * w.abs().max(1.0),
                    "θ {theta}, δ {d}: {fast} vs {w}"
                );
            }
        }
    }

    /// A law made to another secant at one load, on the LTCA's grid (256 positions over one
    /// angular pitch of a 36-tooth driver, loads 1.25 apart, the design load half-way between
    /// two): at the design load every position's secant is the target's — 0.8 to 1.15 × its own,
    /// softer and stiffer — to the inverse's tolerance, first contact stays, and off the design
    /// load the law keeps its stiffening about the new secant: for W = c(δ − e)^p with a series
    /// compliance s added, δ(W) = e + (W/c)^(1/p) + s W, within the Hermite interpolation's
    /// error between knots (0.1 % of the approach).
    #[test]
    fn a_law_takes_the_secant_it_is_given() {
        let n = 256;
        let loads: Vec<f64> = (0..22).map(|k| 80.0 * 1.25f64.powi(k)).collect();
        let p = 1.25;
        let c = |j: usize| 3e10 * (1.0 + 0.3 * (TAU * j as f64 / n as f64).sin());
        let e = |j: usize| 0.5e-6 * (1.0 + (TAU * j as f64 / n as f64).cos());
        let mut law = law_of((0..n).map(|j| power_law(c(j), p, e(j), &loads)).collect());
        law.period = TAU / 36.0;
        let force = 80.0 * 1.25f64.powf(10.5);
        let own = law.secant_stiffness(force, n);
        let factor = |j: usize| 0.8 + 0.35 * (j % 5) as f64 / 4.0;
        let target = |j: usize| factor(j) * own[j];
        let made = law
            .with_secant_at(force, |theta| {
                target((theta / law.period * n as f64).round() as usize % n)
            })
            .expect("compliances leave a stiffness");
        let secant = made.secant_stiffness(force, n);
        for j in 0..n {
            assert_eq!(
                made.knots[j][0].deflection,
                e(j),
                "first contact moved at {j}"
            );
            assert!(
                (secant[j] / target(j) - 1.0).abs() < 1e-6,
                "{j}: {} vs {}",
                secant[j],
                target(j)
            );
            let theta = j as f64 * law.period / n as f64;
            let added = 1.0 / target(j) - 1.0 / own[j];
            for w in [0.37 * force, 2.3 * force, 5.1 * force] {
                let exact = e(j) + (w / c(j)).powf(1.0 / p) + added * w;
                let got = made.deflection_under(theta, w);
                assert!(
                    (got - exact).abs() < 1e-3 * (exact - e(j)),
                    "{j}, {w}: {got} vs {exact}"
                );
            }
        }
        // A target no law can hold (far stiffer than the law at its highest loads) is refused.
        assert!(law.with_secant_at(force, |_| 1e3 * own[0]).is_none());
        assert!(law.with_secant_at(force, |_| f64::NAN).is_none());
    }
}
