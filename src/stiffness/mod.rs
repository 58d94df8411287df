//! The mesh stiffness k(θ) with its unloaded transmission error e(θ) ([`MeshStiffness`], the
//! chain's one currency) and the reference stiffness models (ISO 6336-1, the potential-energy
//! method).
//!
//! # ISO 6336-1:2019, method B (§9)
//! ```text
//! q′    = 0.04723 + 0.15551/z_n1 + 0.25791/z_n2 − 0.00635 x₁ − 0.11654 x₁/z_n1 − 0.00193 x₂
//!         − 0.24188 x₂/z_n2 + 0.00529 x₁² + 0.00182 x₂²                 [mm·µm/N]
//! c′_th = 1/q′,   c′ = c′_th C_M C_R C_B cos β,   C_M = 0.8,  C_R = 1 (solid disc)
//! C_B   = [1 + 0.5 (1.2 − h_fP/m_n)] · [1 − 0.02 (20° − α_n)]
//! c′   ×= (F_t K_A / b / 100)^0.25   if F_t K_A / b < 100 N/mm
//! c_γα  = c′ (0.75 ε_α + 0.25)                                          [N/(mm·µm)]
//! ```
//! c′ is the single-pair stiffness, c_γα the mean mesh stiffness per unit face width; times the
//! face width b they are in N/µm. The standard's model is a solid steel disc gear; it ignores
//! the bore and the rim/web compliance the FE carries down to the bore.

pub mod force_law;
pub mod mesh;
pub mod potential_energy;

pub use force_law::ForceLaw;
pub use mesh::{MeshStiffness, PeriodicTable};

use crate::geometry::GearPair;
use crate::ltca::PositionResult;

/// ISO 6336-1 method B stiffness of a spur pair (SI: N/m).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct IsoStiffness {
    /// Single-pair (maximum) stiffness c′·b [N/m].
    pub single_pair_n_per_m: f64,
    /// Mean mesh stiffness c_γα·b [N/m].
    pub mean_n_per_m: f64,
    /// Theoretical single stiffness c′_th [N/(mm·µm)].
    pub c_th_prime: f64,
    /// Load correction factor applied to c′ (1 at F_t/b ≥ 100 N/mm).
    pub load_factor: f64,
}

impl IsoStiffness {
    /// The mean mesh stiffness c_γα·b as a constant over one base pitch, no unloaded TE.
    pub fn mesh_stiffness(&self, pair: &GearPair, torque: f64) -> MeshStiffness {
        let mut k = MeshStiffness::constant(
            "iso6336 (constant c_gamma_alpha)",
            pair.gears[0].angular_pitch(),
            self.mean_n_per_m,
        );
        k.load_torque = Some(torque);
        k.origin = pair.roll_angle_at(1, pair.contact_points.pitch);
        k
    }
}

/// The LTCA's k(θ) and unloaded TE e(θ) = r_b2 φ₀ over its cycle (positions from the pitch
/// point over one base pitch) at load torque `torque`.
pub fn from_ltca(
    pair: &GearPair,
    results: &[PositionResult],
    torque: f64,
    source: impl Into<String>,
) -> Result<MeshStiffness, String> {
    let rb2 = pair.gears[1].base_radius;
    let angles: Vec<f64> = results.iter().map(|r| r.roll_angle).collect();
    let k: Vec<f64> = results.iter().map(|r| r.mesh_stiffness).collect();
    let e: Vec<f64> = results.iter().map(|r| r.unloaded_te * rb2).collect();
    MeshStiffness::from_samples(
        source,
        Some(torque),
        pair.gears[0].angular_pitch(),
        &angles,
        &k,
        &e,
    )
}

/// ISO 6336-1 method B for spur gears (β = 0, K_A = 1) at load torque `torque` on gear 2,
/// steel against steel (the standard's factors hold for E = 206 GPa; they are scaled by E/206 GPa
/// for other moduli, as ISO 6336-1 §9.3 allows).
pub fn iso_6336_method_b(pair: &GearPair, torque: f64, youngs_modulus: f64) -> IsoStiffness {
    let [g1, g2] = &pair.gears;
    let (z1, z2) = (g1.teeth() as f64, g2.teeth() as f64);
    let (x1, x2) = (g1.spec.profile_shift, g2.spec.profile_shift);
    let q = 0.04723 + 0.15551 / z1 + 0.25791 / z2
        - 0.00635 * x1
        - 0.11654 * x1 / z1
        - 0.00193 * x2
        - 0.24188 * x2 / z2
        + 0.00529 * x1 * x1
        + 0.00182 * x2 * x2;
    let c_th = 1.0 / q;
    let rack = &g1.rack;
    let alpha_deg = rack.pressure_angle.to_degrees();
    let c_b = (1.0 + 0.5 * (1.2 - rack.dedendum_coeff)) * (1.0 - 0.02 * (20.0 - alpha_deg));
    let face_width_mm = g1.spec.face_width.min(g2.spec.face_width) * 1e3;
    // Nominal tangential load on the reference circle.
    let tangential = torque / g2.reference_radius;
    let line_load = tangential / face_width_mm;
    let load_factor = if line_load < 100.0 {
        (line_load / 100.0).powf(0.25)
    } else {
        1.0
    };
    let modulus_factor = youngs_modulus / 206e9;
    let c_prime = c_th * 0.8 * 1.0 * c_b * load_factor * modulus_factor;
    let c_gamma = c_prime * (0.75 * pair.contact_ratio + 0.25);
    // N/(mm·µm) × mm = N/µm = 1e6 N/m.
    IsoStiffness {
        single_pair_n_per_m: c_prime * face_width_mm * 1e6,
        mean_n_per_m: c_gamma * face_width_mm * 1e6,
        c_th_prime: c_th,
        load_factor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    /// Hand calculation for the paper's pair: q′ = 0.04723 + (0.15551 + 0.25791)/36 = 0.058714,
    /// c′_th = 17.032, C_B = 0.975, F_t/b = (143.6/0.05724)/25.4 = 98.77 N/mm → factor 0.99690,
    /// c′ = 13.243, c_γα = 13.243 (0.75·1.69244 + 0.25) = 20.120 N/(mm·µm) → 5.1105e8 N/m.
    #[test]
    fn iso_method_b_for_the_paper_pair() {
        let iso = iso_6336_method_b(&samples::paper36_pair(), 143.6, 206e9);
        assert!((iso.c_th_prime - 17.032).abs() < 1e-3, "{}", iso.c_th_prime);
        assert!(
            (iso.load_factor - 0.99690).abs() < 1e-5,
            "{}",
            iso.load_factor
        );
        assert!(
            (iso.mean_n_per_m / 5.1105e8 - 1.0).abs() < 2e-4,
            "{}",
            iso.mean_n_per_m
        );
    }
}
