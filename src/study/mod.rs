//! The studies behind the commands: a checked [`Case`] and typed options in, a typed result out.
//!
//! One module per command. Each builds its models through the constructors here and in the
//! kernels (the same ones the tests and benches use), runs them, and returns everything a report
//! needs, with the headline numbers as a `Serialize` summary. Studies neither print nor write
//! files (a stiffness file named in the case is the one thing they read): `report` writes their
//! results and the binary prints.

pub mod accuracy;
pub mod checks;
pub mod cluster;
pub mod compare;
pub mod fe;
pub mod fe_sweep;
pub mod frequencies;
pub mod geometry;
pub mod ltca;
pub mod lumped;
pub mod mesh;
pub mod optimize;
pub mod pairs;
pub mod properties;
pub mod quick_validation;
pub mod run;
pub mod stability;
pub mod sweep;
pub mod validate;

use thiserror::Error;

use crate::case::{Case, ReliefVariant};

/// Why a study could not run. Messages say what is wrong and what to change.
#[derive(Debug, Error)]
pub enum StudyError {
    #[error(transparent)]
    Ltca(#[from] crate::ltca::LtcaError),
    #[error(transparent)]
    Fe(#[from] crate::fe::FeError),
    /// An option or a combination of options that cannot run.
    #[error("{0}")]
    Input(String),
    /// A model that would take more memory than the machine has ([`crate::resources`]).
    #[error(transparent)]
    TooLarge(#[from] crate::resources::TooLarge),
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
}

/// The summary of a run that stopped before its end, on request ([`crate::interrupt`]) or
/// because its response diverged: where and why it stopped and how to go on. It takes the place
/// of the finished run's summary.json.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct StoppedEarly {
    pub case: String,
    pub command: String,
    /// Where a stop request ended the run and what is kept.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<String>,
    /// Where the response diverged, the cause and the remedy.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diverged: Option<String>,
    /// The command line that continues it, where the command can resume.
    pub resume: Option<String>,
}

/// Progress of a long study: the stage's name, the work done and the whole.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// A progress sink that shows nothing.
pub fn no_progress(_: &str, _: usize, _: usize) {}

/// The relief variant named, or the case's first; an unknown name lists the case's names.
pub fn relief_variant<'a>(
    case: &'a Case,
    name: Option<&str>,
) -> Result<&'a ReliefVariant, StudyError> {
    match name {
        Some(name) => case.relief_variant(name).ok_or_else(|| {
            StudyError::Input(format!(
                "no relief variant {name:?} in the case; it has {:?}",
                case.relief_variants
                    .iter()
                    .map(|v| v.name.as_str())
                    .collect::<Vec<_>>()
            ))
        }),
        None => case
            .relief_variants
            .first()
            .ok_or_else(|| StudyError::Input("the case has no relief variant".into())),
    }
}

/// Whether `modifications` are no relief at all.
pub fn is_unmodified(modifications: &[crate::geometry::FlankModification; 2]) -> bool {
    modifications.iter().all(|m| m.is_none())
}

/// The name of the unmodified pair in studies and FE runs: the case's own unmodified relief
/// variant, else `none` (the variant the optimizer's baseline and its FE runs add).
pub fn unmodified_name(case: &Case) -> String {
    case.relief_variants
        .iter()
        .find(|v| is_unmodified(&v.modifications))
        .map_or_else(|| "none".to_string(), |v| v.name.clone())
}

/// The load torque on the driven gear: the case's first operating point (the commands'
/// `--torque-nm` sets it).
pub fn load_torque(case: &Case) -> Result<f64, StudyError> {
    case.operating_points
        .first()
        .map(|o| o.torque)
        .ok_or_else(|| {
            StudyError::Input(
                "the case has no operating point: add an [[operating_point]] with speed_rpm and torque_nm".into(),
            )
        })
}

/// `--torque-nm` of the commands: the first operating point's torque.
pub fn torque_override(torque_nm: Option<f64>) -> Option<crate::case::Override> {
    torque_nm.map(|t| crate::case::Override::set("operating_point[0].torque_nm", t))
}

/// Driver speeds from FROM to TO in N equal steps [rpm].
#[derive(Debug, Clone, PartialEq)]
pub struct RpmRange(pub Vec<f64>);

/// The most speeds a range may hold: a sweep of a million speeds takes about ten minutes on
/// two cores (0.6 ms per speed, validation/performance) and half a gigabyte for its points;
/// no spectrum needs more, and a typing slip of a few zeros should not fill the memory.
pub const MAX_SPEEDS: usize = 1_000_000;

impl std::str::FromStr for RpmRange {
    type Err = String;

    /// Parses `FROM:TO:N` with 0 < FROM < TO and N ≥ 2.
    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || {
            format!("{text:?} is invalid: write FROM:TO:N with 0 < FROM < TO and N ≥ 2, e.g. 100:12000:600")
        };
        let parts: Vec<&str> = text.split(':').collect();
        let [from, to, n] = parts[..] else {
            return Err(bad());
        };
        let (from, to): (f64, f64) = (
            from.parse().map_err(|_| bad())?,
            to.parse().map_err(|_| bad())?,
        );
        let n: usize = n.parse().map_err(|_| bad())?;
        if !(from > 0.0 && to > from && to.is_finite() && n >= 2) {
            return Err(bad());
        }
        if n > MAX_SPEEDS {
            return Err(format!(
                "{text:?} asks for {n} speeds, more than the {MAX_SPEEDS} a range may hold \
                 (about 0.6 ms and 500 bytes each): use fewer, or split the range"
            ));
        }
        Ok(RpmRange(
            (0..n)
                .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
                .collect(),
        ))
    }
}
