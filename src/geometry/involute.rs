//! Involute function and its inverse.
//!
//! ```text
//! inv α = tan α − α                       (involute function)
//! roll angle at radius R:  ξ = tan α_R = √(R²/r_b² − 1),   cos α_R = r_b / R
//! ```
//! An involute of the base circle r_b, unwound from polar angle 0, passes through radius R at
//! polar angle inv α_R; its roll angle ξ is the arc length along the line of action from the
//! base-circle tangency point, divided by r_b.

/// The involute function `inv α = tan α − α`.
pub fn involute(alpha: f64) -> f64 {
    alpha.tan() - alpha
}

/// Inverse of the involute function on α ∈ [0, π/2): returns α with `tan α − α = value`.
///
/// Newton's method on `f(α) = tan α − α − v`, `f′(α) = tan² α`, started from the series
/// inverse `α ≈ (3v)^(1/3)` and kept inside a bracket, so it converges for every `v ≥ 0`.
/// Returns `None` for a negative or non-finite value.
pub fn inverse_involute(value: f64) -> Option<f64> {
    if !value.is_finite() || value < 0.0 {
        return None;
    }
    if value == 0.0 {
        return Some(0.0);
    }
    let mut lower = 0.0_f64;
    let mut upper = std::f64::consts::FRAC_PI_2;
    let mut alpha = (3.0 * value).cbrt().min(1.5);
    for _ in 0..100 {
        let residual = involute(alpha) - value;
        if residual > 0.0 {
            upper = alpha;
        } else {
            lower = alpha;
        }
        let slope = alpha.tan().powi(2);
        let mut next = alpha - residual / slope;
        if !(next > lower && next < upper) {
            next = 0.5 * (lower + upper);
        }
        if (next - alpha).abs() <= 1e-15 * alpha.max(1e-300) {
            return Some(next);
        }
        alpha = next;
    }
    Some(alpha)
}

/// Roll angle ξ = √(R²/r_b² − 1) of the involute of base radius `base_radius` at `radius`
/// (0 below the base circle, where no involute exists).
pub fn roll_angle_at_radius(base_radius: f64, radius: f64) -> f64 {
    ((radius / base_radius).powi(2) - 1.0).max(0.0).sqrt()
}

/// Radius R = r_b·√(1 + ξ²) of the involute point with roll angle ξ.
pub fn radius_at_roll_angle(base_radius: f64, roll_angle: f64) -> f64 {
    base_radius * (1.0 + roll_angle * roll_angle).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_involute_round_trips_over_the_useful_range() {
        for i in 1..=170 {
            let alpha = i as f64 * 0.5_f64.to_radians();
            let back = inverse_involute(involute(alpha)).unwrap();
            assert!((back - alpha).abs() < 1e-12, "α = {alpha}: got {back}");
        }
    }

    #[test]
    fn inverse_involute_rejects_negative_values() {
        assert!(inverse_involute(-1e-3).is_none());
        assert!(inverse_involute(f64::NAN).is_none());
    }

    #[test]
    fn roll_angle_and_radius_are_inverse() {
        let rb = 0.053_788;
        for xi in [0.0, 0.1, 0.364, 0.9] {
            let r = radius_at_roll_angle(rb, xi);
            assert!((roll_angle_at_radius(rb, r) - xi).abs() < 1e-12);
        }
    }
}
