//! Speed sweeps of the lumped mesh model: periodic steady state at every driver speed, spectrum
//! of the DTE (rustfft) with the mesh harmonics and the strongest peaks, dynamic factor,
//! separation and Floquet stability; up- and down-sweeps continue from the neighbouring speed so
//! jumps show.
//!
//! Spectrum: a converged steady state repeats every mesh period, so one period holds its whole
//! spectrum (lines at the mesh harmonics only). A point that did not converge (sub-harmonic,
//! quasi-periodic or chaotic response) is integrated [`WINDOW_PERIODS`] periods further and that
//! record is transformed, so lines between the mesh harmonics show with a resolution of
//! f_mesh / [`WINDOW_PERIODS`]. Amplitudes are single-sided: 2|X_k|/N (whole periods, no window
//! needed).

use rayon::prelude::*;

use crate::lumped::{
    largest_modulus, linear_floquet_multipliers, periodic_orbit, record_periods, settle,
    steady_state, MeshModel, State,
};
use crate::signal::{amplitude_spectrum, strongest_lines};

/// Least samples per mesh period (an integer number, so the FFT sees whole periods).
pub const STEPS_PER_PERIOD: usize = 128;

/// RK4 steps per mesh period at driver speed Ω₁: at least [`STEPS_PER_PERIOD`] and 32 per period
/// of the highest natural frequency (at the largest mesh stiffness), so low speeds (many natural
/// periods per mesh period) stay resolved and stable (RK4 needs ωh < 2.8; 32 steps give
/// ωh = 0.2).
pub fn steps_per_period(model: &MeshModel, driver_speed: f64) -> usize {
    let mesh_omega = 2.0 * std::f64::consts::PI * driver_speed / model.mesh.period();
    let ratio = model.highest_frequency() / mesh_omega;
    STEPS_PER_PERIOD.max((32.0 * ratio).ceil() as usize)
}
/// A speed's steady state is reached when the state at period boundaries repeats to this
/// fraction of the static deflection, within at most [`MAX_PERIODS`] mesh periods.
pub const STEADY_TOLERANCE: f64 = 1e-7;
/// The shooting's tolerance for a period-one orbit ([`periodic_orbit`]), of the static
/// deflection: ten times the steady state's, so a settled state is taken as it is.
pub const ORBIT_TOLERANCE: f64 = 1e-6;
pub const MAX_PERIODS: usize = 4000;
/// Mesh harmonics reported.
pub const HARMONICS: usize = 5;
/// Strongest spectral peaks reported per speed.
pub const PEAKS: usize = 3;
/// Mesh periods in the spectrum of a point that did not reach a periodic steady state.
pub const WINDOW_PERIODS: usize = 16;

/// The response at one driver speed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepPoint {
    pub driver_speed_rpm: f64,
    pub mesh_frequency_hz: f64,
    /// Dynamic transmission error along the LOA about its mean: rms and peak-to-peak [m].
    pub dte_rms: f64,
    pub dte_peak_to_peak: f64,
    /// Max dynamic mesh force / static force.
    pub dynamic_factor: f64,
    pub separated: bool,
    /// Amplitudes of the DTE at mesh harmonics 1 … HARMONICS [m].
    pub harmonics: [f64; HARMONICS],
    /// The strongest spectral lines of the DTE (DC excluded): (frequency [Hz], amplitude [m]),
    /// strongest first.
    pub peaks: Vec<(f64, f64)>,
    /// Largest Floquet multiplier of the linearized drive flanks (the tangent stiffness about
    /// the quasi-static state, no separation; > 1: parametrically unstable).
    #[serde(alias = "floquet")]
    pub floquet_linear: f64,
    /// Largest Floquet multiplier of the period-one orbit of the model as integrated (contact
    /// loss, back flanks, force law; [`periodic_orbit`]): at the steady state where it settled,
    /// else the orbit shooting finds (> 1: the periodic response is unstable — a response that
    /// did not settle, or grew without bound); `None` where no period-one orbit was found.
    #[serde(default)]
    pub floquet_orbit: Option<f64>,
    /// Mesh periods integrated for the point, forward and by the shooting ([`settle`]).
    pub periods: usize,
    pub converged: bool,
}

/// Where a sweep's response grew without bound ([`MeshModel::has_diverged`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepDivergence {
    pub driver_speed_rpm: f64,
    /// "up" or "down".
    pub direction: String,
    /// Mesh periods integrated at that speed before the response left the model's range.
    pub periods: usize,
    /// Largest Floquet multiplier of the linearized drive flanks at that speed (> 1: parametric
    /// instability).
    pub floquet_max_multiplier: f64,
    /// Largest Floquet multiplier of the period-one orbit of the model as integrated, where
    /// shooting found one ([`periodic_orbit`]).
    #[serde(default)]
    pub orbit_floquet_max_multiplier: Option<f64>,
    /// The same at the last speed of this direction that settled (its steady state's orbit).
    #[serde(default)]
    pub last_orbit_floquet_max_multiplier: Option<f64>,
    /// The bound it passed [m].
    pub bound_m: f64,
    /// The model's backlash [m] (zero: the back flanks engage as the drive flanks open).
    #[serde(default)]
    pub backlash_m: f64,
}

impl std::fmt::Display for SweepDivergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the lumped response diverged at {:.1} rpm (sweeping {}): after {} mesh periods it was \
             farther than {:.3e} mm from the static state (1000 static deflections)",
            self.driver_speed_rpm,
            self.direction,
            self.periods,
            self.bound_m * 1e3
        )?;
        match (
            self.orbit_floquet_max_multiplier,
            self.last_orbit_floquet_max_multiplier,
        ) {
            (Some(orbit), _) if orbit > 1.0 => write!(
                f,
                ". The periodic response of the model as integrated (contact loss and back \
                 flanks included) exists here but is unstable: its largest Floquet multiplier is \
                 {orbit:.4} > 1 (shooting)"
            )?,
            (None, Some(last)) => write!(
                f,
                ". No periodic response of the model as integrated (contact loss and back flanks \
                 included) was found here (shooting); at the last speed that settled its largest \
                 Floquet multiplier was {last:.4}{}",
                if last > 0.9 {
                    ", near 1: the periodic response ends between the two speeds (a fold or \
                     another bifurcation of the orbit)"
                } else {
                    ""
                }
            )?,
            _ => {}
        }
        if self.floquet_max_multiplier > 1.0 {
            write!(
                f,
                ". The speed lies in a parametric-instability region (largest Floquet multiplier \
                 {:.4} > 1) and the mesh damping is too small to hold the growth: raise the \
                 damping (lumped.damping_ratio or --damping-ratio; 0.02-0.1 is usual for steel \
                 spur gears) or keep the speeds out of the region (`geardyn stability` maps it)",
                self.floquet_max_multiplier
            )
        } else {
            write!(
                f,
                ". The linear model (drive flanks in contact throughout) is stable here (largest \
                 Floquet multiplier {:.4}), so the growth comes from the contact: the teeth \
                 leave the drive flanks (and, at zero backlash, meet the back flanks with their own \
                 k(θ)), and that switching pumps energy in faster than the damping takes it out \
                 (or a mesh harmonic meets an undamped mode). On the paper's pair such \
                 divergences stay at the same speed when the step is cut 8-fold \
                 (validation/lumped); `geardyn validate integrators` checks this case's. Raise \
                 the damping (lumped.damping_ratio or --damping-ratio; 0.02-0.1 is usual for \
                 steel spur gears)",
                self.floquet_max_multiplier
            )?;
            if self.backlash_m <= 0.0 {
                write!(
                    f,
                    ", or give the pair backlash (gear1.thickness_reduction_um, \
                     gear2.thickness_reduction_um), so the teeth separate instead of loading \
                     their back flanks"
                )?;
            }
            Ok(())
        }
    }
}

/// An up-sweep at `refinement` × the sweep's RK4 steps per period, reduced to what a step
/// convergence check compares: the largest dynamic factor before any divergence, and where the
/// response diverged.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefinedUpSweep {
    pub refinement: usize,
    /// RK4 steps per mesh period at the first speed.
    pub steps_per_period: usize,
    /// Speeds that reached neither a steady state nor the divergence bound within
    /// [`MAX_PERIODS`]: left out of the largest dynamic factor.
    pub unsettled: usize,
    /// The largest dynamic factor over the speeds that settled.
    pub max_dynamic_factor: f64,
    pub max_dynamic_factor_rpm: f64,
    /// Where the response diverged ([`MeshModel::has_diverged`]) and after how many periods.
    pub diverged_rpm: Option<f64>,
    pub diverged_periods: Option<usize>,
}

/// The up-sweep of [`sweep`] over `rpms` (each speed's periodic steady state, continued from the
/// previous one's, from the static state) with `refinement` × [`steps_per_period`] RK4 steps.
/// A result that stays put as the step halves is the model's, not the integrator's: the check
/// `geardyn validate integrators` runs across the primary resonance, where the contact
/// switches (RK4 straddles the kinks of the contact law there).
pub fn refined_up_sweep(model: &MeshModel, rpms: &[f64], refinement: usize) -> RefinedUpSweep {
    let mut state = model.static_state();
    let mut out = RefinedUpSweep {
        refinement,
        steps_per_period: rpms.first().map_or(0, |&rpm| {
            steps_per_period(model, rpm * 2.0 * std::f64::consts::PI / 60.0) * refinement
        }),
        unsettled: 0,
        max_dynamic_factor: 0.0,
        max_dynamic_factor_rpm: f64::NAN,
        diverged_rpm: None,
        diverged_periods: None,
    };
    for &rpm in rpms {
        let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
        let steps = steps_per_period(model, speed) * refinement;
        let s = steady_state(model, speed, steps, state, STEADY_TOLERANCE, MAX_PERIODS);
        if s.diverged {
            out.diverged_rpm = Some(rpm);
            out.diverged_periods = Some(s.periods);
            break;
        }
        state = s.start;
        if !s.converged {
            out.unsettled += 1;
            continue;
        }
        let factor = s.dynamic_factor(model.force);
        if factor > out.max_dynamic_factor {
            out.max_dynamic_factor = factor;
            out.max_dynamic_factor_rpm = rpm;
        }
    }
    out
}

fn analyse(
    (model, linear): (&MeshModel, &MeshModel),
    rpm: f64,
    start: State,
    direction: &str,
) -> Result<(SweepPoint, State), SweepDivergence> {
    let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
    let steps = steps_per_period(model, speed);
    let (s, settled_orbit) = settle(model, speed, steps, start, STEADY_TOLERANCE, MAX_PERIODS);
    // The orbit where the response settled; else the one shooting finds from where this
    // speed started (unstable, or the response would have settled on it).
    let orbit = |from: State| {
        periodic_orbit(model, speed, steps, from, ORBIT_TOLERANCE).map(|o| o.max_multiplier())
    };
    if s.diverged {
        return Err(SweepDivergence {
            driver_speed_rpm: rpm,
            direction: direction.into(),
            periods: s.periods,
            floquet_max_multiplier: largest_modulus(&linear_floquet_multipliers(
                linear, speed, steps,
            )),
            orbit_floquet_max_multiplier: orbit(start),
            last_orbit_floquet_max_multiplier: None,
            bound_m: model.divergence_bound(),
            backlash_m: model.backlash.unwrap_or(0.0),
        });
    }
    let rms = crate::signal::rms_about_mean(&s.displacement);
    let (lo, hi) = crate::signal::extremes(&s.displacement);
    let mesh_hz = speed / model.mesh.period();
    let (record, periods) = if s.converged {
        (s.displacement.clone(), 1)
    } else {
        (
            record_periods(model, speed, steps, s.start, WINDOW_PERIODS),
            WINDOW_PERIODS,
        )
    };
    let spectrum = amplitude_spectrum(&record);
    let harmonics = std::array::from_fn(|h| spectrum[(h + 1) * periods - 1]);
    let peaks = strongest_lines(&spectrum, PEAKS)
        .into_iter()
        .map(|(line, amplitude)| (line as f64 / periods as f64 * mesh_hz, amplitude))
        .collect();
    let point = SweepPoint {
        driver_speed_rpm: rpm,
        mesh_frequency_hz: mesh_hz,
        dte_rms: rms,
        dte_peak_to_peak: hi - lo,
        dynamic_factor: s.dynamic_factor(model.force),
        separated: s.separated,
        harmonics,
        peaks,
        floquet_linear: largest_modulus(&linear_floquet_multipliers(linear, speed, steps)),
        floquet_orbit: match settled_orbit {
            Some(o) => Some(o.max_multiplier()),
            None => orbit(s.start),
        },
        periods: s.periods,
        converged: s.converged,
    };
    Ok((point, s.start))
}

/// Up-sweep and down-sweep over `rpms` (ascending), run in parallel with each other; each
/// continues from the previous speed's steady state. Fails where the response diverges.
pub fn sweep(
    model: &MeshModel,
    rpms: &[f64],
) -> Result<(Vec<SweepPoint>, Vec<SweepPoint>), SweepDivergence> {
    let done = continue_sweep(model, rpms, SweepProgress::start(model), &|| false);
    match done.diverged {
        Some(divergence) => Err(divergence),
        None => Ok(done.into_points()),
    }
}

/// A sweep part done: the points of each direction so far and the steady state the next speed
/// continues from, so an interrupted sweep resumes exactly where it stopped.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SweepProgress {
    /// Up-sweep points, ascending speed.
    pub up: Vec<SweepPoint>,
    pub up_state: State,
    /// Down-sweep points in the order swept (descending speed).
    pub down: Vec<SweepPoint>,
    pub down_state: State,
    /// Where a direction diverged (the first found); that direction stops there, the points
    /// before it are kept.
    pub diverged: Option<SweepDivergence>,
}

impl SweepProgress {
    /// Nothing done: both directions start from the static equilibrium.
    pub fn start(model: &MeshModel) -> Self {
        SweepProgress {
            up: Vec::new(),
            up_state: model.static_state(),
            down: Vec::new(),
            down_state: model.static_state(),
            diverged: None,
        }
    }

    /// Whether both directions cover all `speeds`.
    pub fn is_complete(&self, speeds: usize) -> bool {
        self.up.len() == speeds && self.down.len() == speeds
    }

    /// The up- and down-sweep, both in ascending speed.
    pub fn into_points(self) -> (Vec<SweepPoint>, Vec<SweepPoint>) {
        let mut down = self.down;
        down.reverse();
        (self.up, down)
    }
}

/// Continues `progress` over `rpms` (ascending) until both directions are done, one diverges
/// (`diverged`; the other goes on) or `stop` returns true (asked before each speed); the two
/// directions run in parallel. A sweep continued from its own progress gives the same points,
/// bit for bit, as one run through.
pub fn continue_sweep(
    model: &MeshModel,
    rpms: &[f64],
    progress: SweepProgress,
    stop: &(dyn Fn() -> bool + Sync),
) -> SweepProgress {
    // The drive flanks' linearization does not depend on the speed: once for the sweep.
    let linear = model.linearized();
    let run = |order: Vec<f64>, mut points: Vec<SweepPoint>, mut state: State, direction| {
        for rpm in order.into_iter().skip(points.len()) {
            if stop() {
                break;
            }
            match analyse((model, &linear), rpm, state, direction) {
                Ok((point, next)) => {
                    state = next;
                    points.push(point);
                }
                Err(divergence) => {
                    let last = points.last().and_then(|p: &SweepPoint| p.floquet_orbit);
                    let divergence = SweepDivergence {
                        last_orbit_floquet_max_multiplier: last,
                        ..divergence
                    };
                    return (points, state, Some(divergence));
                }
            }
        }
        (points, state, None)
    };
    let SweepProgress {
        up,
        up_state,
        down,
        down_state,
        diverged,
    } = progress;
    if diverged.is_some() {
        return SweepProgress {
            up,
            up_state,
            down,
            down_state,
            diverged,
        };
    }
    let ((up, up_state, up_diverged), (down, down_state, down_diverged)) = rayon::join(
        || run(rpms.to_vec(), up, up_state, "up"),
        || {
            run(
                rpms.iter().rev().copied().collect(),
                down,
                down_state,
                "down",
            )
        },
    );
    SweepProgress {
        up,
        up_state,
        down,
        down_state,
        diverged: up_diverged.or(down_diverged),
    }
}

/// Driver speeds [rpm] of the local maxima of `values` (strict, interior points).
pub fn peaks(rpms: &[f64], values: &[f64]) -> Vec<f64> {
    (1..values.len().saturating_sub(1))
        .filter(|&i| values[i] > values[i - 1] && values[i] >= values[i + 1])
        .map(|i| rpms[i])
        .collect()
}

/// Independent points in parallel (no continuation), for maps such as Floquet stability: the
/// largest multiplier of the linearized drive flanks at each speed.
pub fn floquet_map(model: &MeshModel, rpms: &[f64]) -> Vec<f64> {
    let linear = model.linearized();
    rpms.par_iter()
        .map(|rpm| {
            let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
            let steps = steps_per_period(model, speed);
            largest_modulus(&linear_floquet_multipliers(&linear, speed, steps))
        })
        .collect()
}

/// The largest Floquet multiplier of the period-one orbit of the model as integrated at each
/// speed ([`periodic_orbit`], shooting from the quasi-static state, each speed on its own, in
/// parallel); `None` where no orbit was found.
pub fn orbit_floquet_map(model: &MeshModel, rpms: &[f64]) -> Vec<Option<f64>> {
    rpms.par_iter()
        .map(|rpm| {
            let speed = rpm * 2.0 * std::f64::consts::PI / 60.0;
            let steps = steps_per_period(model, speed);
            let guess = model.quasi_static_state(0.0);
            periodic_orbit(model, speed, steps, guess, ORBIT_TOLERANCE).map(|o| o.max_multiplier())
        })
        .collect()
}
