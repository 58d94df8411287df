//! The plan of `geardyn run`, the main job: which stages run, on which speeds, with which
//! explicit-FE cross-checks. The binary carries it out stage by stage (each stage is a command's
//! study, written into its own sub-folder).

use super::optimize::FeCheckPlan;
use super::RpmRange;

/// The stages in order, as the progress lines name them.
/// The relief stage comes before the FE stiffness stage so that the explicit runs of both (the
/// unmodified pair's stiffness run is the cross-check's baseline) run side by side; the binary
/// names it by its number (3).
pub const STAGES: [&str; 6] = [
    "geometry and meshes",
    "LTCA",
    "relief optimization and its FE cross-check",
    "FE stiffness from the low-speed DTE",
    "rpm sweeps (LTCA and FE k) and stability",
    "FE against lumped frequencies",
];

/// What one `geardyn run` does.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPlan {
    /// Speeds of the sweeps on the LTCA's and the FE's k(θ) [rpm].
    pub sweep_rpm: RpmRange,
    /// Speeds of the stability map [rpm].
    pub stability_rpm: RpmRange,
    /// LTCA positions per base pitch.
    pub ltca_positions: usize,
    /// The relief candidates and scenes the explicit FE checks.
    pub fe_check: FeCheckPlan,
    /// FE speeds of the frequency comparison beyond the cross-check's own high-speed run
    /// (which it uses when there is one) [rpm].
    pub compare_speeds_rpm: Vec<f64>,
    /// Use the cross-check's high-speed run of the unmodified pair in the comparison.
    pub compare_high_speed_run: bool,
    /// Positions of the FE modal analysis.
    pub modal_positions: usize,
    /// Also the labelled paper-stiffness study (needs an FE run at speed).
    pub paper_stiffness: bool,
    /// Also the explicit FE's speed sweep through the resonance
    /// ([`super::compare::fe_sweep_speeds`]).
    pub fe_sweep: bool,
}

impl RunPlan {
    /// The default job (about 4 minutes on 2 cores: the explicit FE of the unmodified pair and
    /// of the optimum at low speed, side by side), or with `full` every cross-check (hours).
    pub fn new(full: bool) -> Self {
        let range = |from: f64, to: f64, n: usize| {
            RpmRange(
                (0..n)
                    .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
                    .collect(),
            )
        };
        RunPlan {
            sweep_rpm: range(100.0, 12000.0, 600),
            stability_rpm: range(100.0, 20000.0, 2000),
            ltca_positions: 64,
            fe_check: if full {
                FeCheckPlan::full()
            } else {
                FeCheckPlan::baseline_and_best()
            },
            compare_speeds_rpm: if full {
                vec![1200.0, 4800.0]
            } else {
                Vec::new()
            },
            compare_high_speed_run: full,
            // Without FE runs at speed the explicit mesh's modes label nothing: 4 positions keep
            // its rows; the headline frequencies come from the case's mesh (compare).
            modal_positions: if full { 16 } else { 4 },
            paper_stiffness: full,
            fe_sweep: full,
        }
    }
}
