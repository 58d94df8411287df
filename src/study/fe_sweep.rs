//! The explicit FE's speed sweep through the mesh resonance against the lumped twin
//! (`geardyn compare --fe-sweep FROM:TO:N`).
//!
//! At each FE speed: the DTE's first mesh-harmonic amplitude and its rms about the mean, in the
//! statistics window after the ramp's ringing ([`super::compare::SpeedComparison`]). The lumped
//! twin (speed drive, elastic bodies, the FE's k(θ) and mesh damping, [`super::compare`]) is swept
//! over the same range four times as densely. The resonance speed of each is the peak of a
//! one-degree-of-freedom response |X(n)| = A/√((1 − r²)² + (2ζr)²), r = n/n_r, fitted to the
//! first-harmonic amplitudes by least squares ([`resonance_fit`]): between eight FE speeds the
//! fit places the peak where the samples' shape puts it, not at the nearest sample.

use serde::Serialize;

use super::compare::SpeedComparison;

/// One speed of the FE sweep against the lumped twin.
#[derive(Debug, Clone, Serialize)]
pub struct SweepSpeed {
    pub speed_rpm: f64,
    /// First mesh-harmonic amplitude and rms about the mean of the DTE [rad].
    pub fe_mesh_amplitude_rad: f64,
    pub lumped_mesh_amplitude_rad: f64,
    pub fe_dte_rms_rad: f64,
    pub lumped_dte_rms_rad: f64,
    pub dte_rms_rel_err: f64,
    /// Whether the lumped twin reached a periodic steady state there.
    pub lumped_converged: bool,
    /// The FE's statistics window [s] (after the ramp's ringing).
    pub fe_window_s: (f64, f64),
}

/// The FE sweep's headline numbers (`fe_sweep` in compare's summary).
#[derive(Debug, Clone, Serialize)]
pub struct FeSweep {
    pub speeds: Vec<SweepSpeed>,
    /// The lumped twin's dense curve: (rpm, first-harmonic amplitude [rad], DTE rms [rad]).
    pub lumped_curve: Vec<(f64, f64, f64)>,
    /// Resonance speeds from the fitted peaks [rpm], and the fits' damping ratios.
    pub resonance_rpm_fe: f64,
    pub resonance_rpm_lumped: f64,
    pub resonance_rpm_rel_err: f64,
    pub fitted_damping_ratio_fe: f64,
    pub fitted_damping_ratio_lumped: f64,
    /// The largest first-harmonic amplitude of each (the fitted peak) and lumped/FE − 1.
    pub peak_dte_mesh_amplitude_fe_rad: f64,
    pub peak_dte_mesh_amplitude_lumped_rad: f64,
    pub peak_dte_mesh_amplitude_rel_err: f64,
    /// The largest |lumped/FE − 1| of the DTE rms over the FE speeds.
    pub dte_rms_max_rel_err: f64,
    /// How each FE run settled: its statistics window against the mesh mode's decay time.
    pub settling_note: String,
}

/// The peak of a one-degree-of-freedom response fitted to `points` (speed, amplitude > 0):
/// |X(n)| = A/√((1 − r²)² + (2ζr)²), r = n/n_r, A by linear least squares for each (n_r, ζ),
/// (n_r, ζ) by a grid over the points' speed range and ζ ∈ [0.005, 0.5] (log), refined by
/// narrowing the grid about the best three times. Returns the fitted curve's peak: its speed
/// n_r√(1 − 2ζ²), ζ, and its amplitude A/(2ζ√(1 − ζ²)); `None` with fewer than three points.
pub fn resonance_fit(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let points: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.1.is_finite())
        .collect();
    if points.len() < 3 {
        return None;
    }
    let shape = |n: f64, nr: f64, zeta: f64| {
        let r = n / nr;
        1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt()
    };
    // Relative residual: every point weighs alike whatever its amplitude.
    let cost = |nr: f64, zeta: f64| {
        let (mut num, mut den) = (0.0, 0.0);
        for &(n, y) in &points {
            let h = shape(n, nr, zeta) / y;
            num += h;
            den += h * h;
        }
        let a = num / den;
        let residual: f64 = points
            .iter()
            .map(|&(n, y)| (a * shape(n, nr, zeta) / y - 1.0).powi(2))
            .sum();
        (residual, a)
    };
    let (lo, hi) = points.iter().fold((f64::INFINITY, 0.0f64), |(l, h), p| {
        (l.min(p.0), h.max(p.0))
    });
    let (mut nr_range, mut log_zeta_range) = ((lo, hi), (0.005f64.ln(), 0.5f64.ln()));
    let mut best = (f64::INFINITY, lo, 0.05, 0.0);
    for _ in 0..4 {
        for i in 0..=200 {
            let nr = nr_range.0 + (nr_range.1 - nr_range.0) * i as f64 / 200.0;
            for j in 0..=60 {
                let zeta = (log_zeta_range.0
                    + (log_zeta_range.1 - log_zeta_range.0) * j as f64 / 60.0)
                    .exp();
                let (c, a) = cost(nr, zeta);
                if c < best.0 {
                    best = (c, nr, zeta, a);
                }
            }
        }
        let (dn, dz) = (
            (nr_range.1 - nr_range.0) / 20.0,
            (log_zeta_range.1 - log_zeta_range.0) / 20.0,
        );
        nr_range = (best.1 - dn, best.1 + dn);
        log_zeta_range = (best.2.ln() - dz, best.2.ln() + dz);
    }
    let (_, nr, zeta, a) = best;
    let peak = a / (2.0 * zeta * (1.0 - zeta * zeta).max(1e-12).sqrt());
    Some((nr * (1.0 - 2.0 * zeta * zeta).max(0.0).sqrt(), zeta, peak))
}

/// Summarizes the FE speeds `speeds` (their comparisons with the lumped twin) and the twin's
/// dense `curve` (rpm, first-harmonic amplitude, rms, all [rad]); `decay_time_s` is the mesh
/// mode's 1/(ζω_n), which each FE run's settling window is measured against.
pub fn summarize(
    speeds: &[SpeedComparison],
    curve: Vec<(f64, f64, f64)>,
    decay_time_s: f64,
) -> Option<FeSweep> {
    let rows: Vec<SweepSpeed> = speeds
        .iter()
        .map(|s| SweepSpeed {
            speed_rpm: s.speed_rpm,
            fe_mesh_amplitude_rad: s.fe_harmonics_rad.first().copied().unwrap_or(f64::NAN),
            lumped_mesh_amplitude_rad: s.lumped_harmonics_rad.first().copied().unwrap_or(f64::NAN),
            fe_dte_rms_rad: s.fe_dte_rms_rad,
            lumped_dte_rms_rad: s.lumped_dte_rms_rad,
            dte_rms_rel_err: s.lumped_dte_rms_rad / s.fe_dte_rms_rad - 1.0,
            lumped_converged: s.lumped_converged,
            fe_window_s: s.late_window_s,
        })
        .collect();
    let fe_points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.speed_rpm, r.fe_mesh_amplitude_rad))
        .collect();
    let lumped_points: Vec<(f64, f64)> = curve.iter().map(|c| (c.0, c.1)).collect();
    let (fe_rpm, fe_zeta, fe_peak) = resonance_fit(&fe_points)?;
    let (lumped_rpm, lumped_zeta, lumped_peak) = resonance_fit(&lumped_points)?;
    let dte_rms_max_rel_err = rows
        .iter()
        .map(|r| r.dte_rms_rel_err.abs())
        .fold(0.0, f64::max);
    // The shortest time between a run's ramp end (its window start less the ringing) and its
    // window: how many decay times the response had to settle.
    let settled = rows
        .iter()
        .map(|r| r.fe_window_s.0 / decay_time_s)
        .fold(f64::INFINITY, f64::min);
    Some(FeSweep {
        speeds: rows,
        lumped_curve: curve,
        resonance_rpm_fe: fe_rpm,
        resonance_rpm_lumped: lumped_rpm,
        resonance_rpm_rel_err: lumped_rpm / fe_rpm - 1.0,
        fitted_damping_ratio_fe: fe_zeta,
        fitted_damping_ratio_lumped: lumped_zeta,
        peak_dte_mesh_amplitude_fe_rad: fe_peak,
        peak_dte_mesh_amplitude_lumped_rad: lumped_peak,
        peak_dte_mesh_amplitude_rel_err: lumped_peak / fe_peak - 1.0,
        dte_rms_max_rel_err,
        settling_note: format!(
            "each FE run's statistics window starts at least {settled:.1} decay times 1/(ζω_n) of the mesh mode after its start (the ramp included); the amplitude left of a start transient is e^-{settled:.1} of it"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::resonance_fit;

    /// A synthetic one-degree-of-freedom response sampled at eight speeds from 0.8 to 1.2 × its
    /// resonance (as the FE sweep samples): the fit returns the resonance, the damping and the
    /// peak it was made with, though no sample sits on the peak.
    #[test]
    fn the_fit_recovers_a_known_resonance() {
        for (nr, zeta) in [(5470.0, 0.05), (5200.0, 0.03), (6100.0, 0.12)] {
            let a = 2.0e-5;
            let points: Vec<(f64, f64)> = (0..8)
                .map(|i| {
                    let n = nr * (0.8 + 0.4 * i as f64 / 7.0 + 0.013);
                    let r: f64 = n / nr;
                    (
                        n,
                        a / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt(),
                    )
                })
                .collect();
            let (got_nr, got_zeta, peak) = resonance_fit(&points).unwrap();
            let true_peak = a / (2.0 * zeta * (1.0 - zeta * zeta).sqrt());
            let peak_speed = nr * (1.0 - 2.0 * zeta * zeta).sqrt();
            assert!(
                (got_nr / peak_speed - 1.0).abs() < 1e-4,
                "{got_nr} vs {peak_speed}"
            );
            assert!((got_zeta / zeta - 1.0).abs() < 1e-2, "{got_zeta} vs {zeta}");
            assert!(
                (peak / true_peak - 1.0).abs() < 1e-2,
                "{peak} vs {true_peak}"
            );
        }
    }
}
