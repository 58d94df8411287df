//! Safety factors against the material's limits, statically and under the dynamic mesh force.
//!
//! ```text
//! S_F = σ_Flim Y_ST / σ_F        Y_ST = 2 (the reference test gear's stress correction)
//! S_H = σ_Hlim / σ_H
//! ```
//! σ_F, σ_H at the design torque (the FE's fillet maximum or ISO 6336-3's σ_F0; the LTCA's
//! largest Hertz pressure or ISO 6336-2's σ_H); the life, size, notch-sensitivity, surface,
//! lubrication and work-hardening factors of ISO 6336-2/-3/-5 are 1 (a case gives none of them),
//! and so are the load factors K_A, K_Hβ, K_Hα. Under a dynamic mesh force K times the static one
//! (the sweep's dynamic factor at a speed), the root stress grows as K and the Hertz pressure as
//! √K (p ∝ √W), so S_F/K and S_H/√K.

/// The stress correction factor of the standard reference test gear (ISO 6336-3, -5).
pub const TEST_GEAR_STRESS_CORRECTION: f64 = 2.0;

/// S_F for the root stress `stress` against σ_Flim `limit` (same units).
pub fn root_safety(stress: f64, limit: f64) -> f64 {
    limit * TEST_GEAR_STRESS_CORRECTION / stress
}

/// S_H for the contact pressure `stress` against σ_Hlim `limit` (same units).
pub fn contact_safety(stress: f64, limit: f64) -> f64 {
    limit / stress
}

/// (S_F, S_H) under a mesh force `dynamic_factor` times the static one, from their static values.
pub fn under_dynamic_load(root: f64, contact: f64, dynamic_factor: f64) -> (f64, f64) {
    (root / dynamic_factor, contact / dynamic_factor.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strength::hertz::line_contact;

    /// The dynamic scaling is the stresses' own: doubling the force doubles the root stress of
    /// a linear body and raises Hertz's pressure by √2 (line_contact at 2W against W).
    #[test]
    fn a_dynamic_load_scales_the_safety_as_the_stresses_do() {
        let (root, contact) = (root_safety(250e6, 500e6), contact_safety(1000e6, 1500e6));
        assert!((root - 4.0).abs() < 1e-12 && (contact - 1.5).abs() < 1e-12);
        let (p1, _) = line_contact(1000.0, 0.02, [0.01, 0.02], 1.1e11);
        let (p2, _) = line_contact(2000.0, 0.02, [0.01, 0.02], 1.1e11);
        let (root2, contact2) = under_dynamic_load(root, contact, 2.0);
        assert!((root2 - 2.0).abs() < 1e-12);
        assert!((contact2 - contact_safety(1000e6 * p2 / p1, 1500e6)).abs() < 1e-12);
    }
}
