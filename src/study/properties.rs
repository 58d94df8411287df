//! Property check of case parsing and geometry (`geardyn validate properties`): generated
//! cases — the embedded case with one to four keys changed to a plausible value, a value out of
//! range (zero, negative, huge, tiny, NaN, infinite), a value of the wrong type, or the key
//! removed — each either gives a case whose every geometry output is finite, or a clear error
//! that names the parameter. Never a panic.
//!
//! Each sample draws from its own generator seeded with (seed, index), so a sample is the same
//! whatever the thread count, and a failing one is re-made from its index alone.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;

use crate::case::{Case, Override};
use crate::geometry::GearIndex;

/// A key the generator changes, with the range of plausible values.
struct Key {
    key: &'static str,
    low: f64,
    high: f64,
    integer: bool,
}

const fn key(key: &'static str, low: f64, high: f64) -> Key {
    Key {
        key,
        low,
        high,
        integer: false,
    }
}

const fn integer(key: &'static str, low: f64, high: f64) -> Key {
    Key {
        key,
        low,
        high,
        integer: true,
    }
}

/// The keys and their plausible ranges: gears a designer might ask for, some of which are
/// impossible together (undercut, interference, a bore through the root, contact ratio < 1).
const KEYS: [Key; 31] = [
    key("tool.module_mm", 0.5, 10.0),
    key("tool.pressure_angle_deg", 14.5, 25.0),
    key("tool.dedendum_coeff", 1.1, 1.4),
    key("tool.tip_radius_coeff", 0.1, 0.4),
    integer("gear1.teeth", 8.0, 150.0),
    key("gear1.profile_shift", -0.6, 0.8),
    key("gear1.addendum_coeff", 0.8, 1.2),
    key("gear1.face_width_mm", 5.0, 100.0),
    key("gear1.bore_radius_mm", 0.0, 60.0),
    key("gear1.thickness_reduction_um", 0.0, 50.0),
    integer("gear2.teeth", 8.0, 150.0),
    key("gear2.profile_shift", -0.6, 0.8),
    key("gear2.addendum_coeff", 0.8, 1.2),
    key("gear2.face_width_mm", 5.0, 100.0),
    key("gear2.bore_radius_mm", 0.0, 60.0),
    key("pair.center_distance_mm", 100.0, 130.0),
    key("material.youngs_modulus_gpa", 70.0, 250.0),
    key("material.poisson_ratio", 0.2, 0.35),
    key("material.density_kg_per_m3", 2000.0, 9000.0),
    key("operating_point[0].speed_rpm", 10.0, 20000.0),
    key("operating_point[0].torque_nm", 1.0, 2000.0),
    key("relief_variant[1].gear1.tip.amount_um", 0.0, 60.0),
    key("relief_variant[1].gear2.root.amount_um", 0.0, 60.0),
    key("mesh.fine_element_mm", 0.05, 2.0),
    key("mesh.coarse_element_mm", 0.5, 5.0),
    key("fe.step_factor", 0.1, 1.0),
    key("fe.penalty_factor", 0.1, 10.0),
    key("fe.output_interval_us", 1.0, 100.0),
    key("lumped.damping_ratio", 0.0, 0.2),
    key("scene[0].duration_s", 0.001, 0.2),
    key("scene[0].ramp_s", 0.0, 0.05),
];

/// How a key was changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Change {
    Plausible,
    OutOfRange,
    WrongType,
    Removed,
}

/// The changes that make one generated case from the embedded one.
pub type Changes = Vec<(Override, Change)>;

/// One generated case: the changes made to the embedded one.
pub fn sample(seed: u64, index: u64) -> Changes {
    let mut rng = StdRng::seed_from_u64(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let count = rng.random_range(1..=4);
    (0..count)
        .map(|_| {
            let k = &KEYS[rng.random_range(0..KEYS.len())];
            let draw: f64 = rng.random();
            let plausible = |rng: &mut StdRng| {
                let x = rng.random_range(k.low..=k.high);
                if k.integer {
                    toml::Value::Integer(x.round() as i64)
                } else {
                    toml::Value::Float(x)
                }
            };
            if draw < 0.6 {
                (Override::set(k.key, plausible(&mut rng)), Change::Plausible)
            } else if draw < 0.85 {
                let value = match rng.random_range(0..6) {
                    0 => 0.0,
                    1 => -rng.random_range(k.low.max(1e-3)..=k.high.max(1.0)),
                    2 => 1e12,
                    3 => 1e-12,
                    4 => f64::NAN,
                    _ => f64::INFINITY,
                };
                let value = if k.integer && value.is_finite() && value.abs() < 1e15 {
                    toml::Value::Integer(value as i64)
                } else {
                    toml::Value::Float(value)
                };
                (Override::set(k.key, value), Change::OutOfRange)
            } else if draw < 0.95 {
                let value = if rng.random_bool(0.5) {
                    toml::Value::String("abc".into())
                } else {
                    toml::Value::Boolean(true)
                };
                (Override::set(k.key, value), Change::WrongType)
            } else {
                (
                    Override::Remove {
                        key: k.key.to_string(),
                    },
                    Change::Removed,
                )
            }
        })
        .collect()
}

/// What one sample gave.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "outcome", content = "detail")]
pub enum Outcome {
    /// A case with every geometry output finite.
    Valid,
    /// Rejected with a message that names a changed key (or its last part).
    Rejected,
    /// Rejected, but the message names none of the changed parameters.
    Unnamed(String),
    /// A valid case with a NaN or infinite output: what and where.
    NotFinite(String),
    Panicked(String),
}

/// Runs one sample.
pub fn check(changes: &[(Override, Change)]) -> Outcome {
    let overrides: Vec<Override> = changes.iter().map(|(o, _)| o.clone()).collect();
    let result = std::panic::catch_unwind(|| match Case::load_with(None, &overrides) {
        Err(e) => {
            let message = e.to_string();
            if names_a_parameter(&message, changes) {
                Outcome::Rejected
            } else {
                Outcome::Unnamed(message)
            }
        }
        Ok(case) => match non_finite_output(&case) {
            Some(what) => Outcome::NotFinite(what),
            None => Outcome::Valid,
        },
    });
    result.unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Outcome::Panicked(message)
    })
}

/// Whether `message` names a parameter of the case file precisely: a changed key by its path
/// (`gear1.teeth`; an array entry's key by its index and name, `scene[0]` … `.duration_s`, or
/// by its path inside the entry, `gear1.tip.amount_um`), as the TOML line that holds it
/// (`teeth = "abc"`) or as a missing field (`` `teeth` ``); or, for a limit another parameter
/// sets, any key of the case file by its full `section.key`.
fn names_a_parameter(message: &str, changes: &[(Override, Change)]) -> bool {
    let changed = changes.iter().any(|(o, _)| {
        let key = match o {
            Override::Set { key, .. } | Override::Remove { key } => key.as_str(),
            Override::Append { array, .. } => array.as_str(),
        };
        let last = key.rsplit('.').next().unwrap_or(key);
        let in_entry = match key.split_once("].") {
            Some((entry, inner)) => {
                message.contains(&format!("{entry}]")) && message.contains(&format!(".{inner}"))
                    || inner.contains('.') && message.contains(inner)
            }
            None => false,
        };
        message.contains(key)
            || in_entry
            || message.contains(&format!("{last} ="))
            || message.contains(&format!("`{last}`"))
    });
    changed || case_keys().iter().any(|k| message.contains(k.as_str()))
}

/// Every key of the embedded case's tables as `section.key`, and the dotted keys inside its
/// arrays of tables (`gear1.tip.amount_um` of a relief variant).
fn case_keys() -> &'static [String] {
    static KEYS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    KEYS.get_or_init(|| {
        let table: toml::Table = crate::case::EMBEDDED_DEFAULT
            .parse()
            .expect("the embedded case parses");
        let mut keys = Vec::new();
        for (section, value) in &table {
            match value {
                toml::Value::Table(inner) => {
                    keys.extend(inner.keys().map(|k| format!("{section}.{k}")))
                }
                toml::Value::Array(entries) => {
                    for entry in entries.iter().filter_map(|e| e.as_table()) {
                        dotted(entry, String::new(), &mut keys);
                    }
                }
                _ => {}
            }
        }
        keys
    })
}

/// The first NaN or infinite number among the case's geometry outputs (the summary `geardyn
/// geometry` writes, every tooth outline of every relief variant, the Hertzian pressure).
fn non_finite_output(case: &Case) -> Option<String> {
    let summary = super::geometry::GeometrySummary::new(case);
    if let Some(path) = toml::Value::try_from(&summary)
        .ok()
        .and_then(|v| first_non_finite(&v, String::new()))
    {
        return Some(format!("geometry summary: {path}"));
    }
    for variant in &case.relief_variants {
        for (i, modification) in variant.modifications.iter().enumerate() {
            let index: GearIndex = i + 1;
            let outline = case
                .pair
                .gear(index)
                .tooth_outline(modification, crate::geometry::OutlineResolution::default());
            if let Some(p) = outline
                .iter()
                .find(|p| !(p.position.x.is_finite() && p.position.y.is_finite()))
            {
                return Some(format!(
                    "gear {index}'s outline with relief {}: point {:?}",
                    variant.name, p.position
                ));
            }
        }
    }
    let pressure = case.hertz_pressure_pitch();
    (!pressure.is_finite()).then(|| format!("Hertzian pressure {pressure}"))
}

fn first_non_finite(value: &toml::Value, path: String) -> Option<String> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Some(format!("{path} = {x}")),
        toml::Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, v)| first_non_finite(v, format!("{path}[{i}]"))),
        toml::Value::Table(table) => table
            .iter()
            .find_map(|(k, v)| first_non_finite(v, format!("{path}.{k}"))),
        _ => None,
    }
}

/// A failing sample, to re-make from its index.
#[derive(Debug, Clone, Serialize)]
pub struct Failure {
    pub index: u64,
    pub changes: Vec<String>,
    pub outcome: Outcome,
}

/// The tally (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct PropertyReport {
    pub seed: u64,
    pub cases: usize,
    pub valid: usize,
    pub rejected: usize,
    pub unnamed: usize,
    pub not_finite: usize,
    pub panicked: usize,
    /// Valid cases among those whose changes were all plausible values: the generator's check
    /// on itself (a generator that made only broken cases would pass everything else).
    pub plausible_cases: usize,
    pub plausible_valid_share: f64,
    /// The first failures by sample index (at most 20).
    pub failures: Vec<Failure>,
    pub wall_s: f64,
}

impl PropertyReport {
    /// No panic, no NaN, every rejection names its parameter.
    pub fn passed(&self) -> bool {
        self.unnamed == 0 && self.not_finite == 0 && self.panicked == 0
    }
}

/// Failures kept in the report, the first by index.
const KEPT_FAILURES: usize = 20;

/// Counts over a share of the samples; shares merge in any order to the same tally (the kept
/// failures are the first by index), so memory stays flat in the number of cases.
#[derive(Debug, Default)]
struct Tally {
    valid: usize,
    rejected: usize,
    unnamed: usize,
    not_finite: usize,
    panicked: usize,
    plausible: usize,
    plausible_valid: usize,
    failures: Vec<Failure>,
}

impl Tally {
    fn add(mut self, index: u64, changes: &Changes, outcome: Outcome) -> Self {
        match &outcome {
            Outcome::Valid => self.valid += 1,
            Outcome::Rejected => self.rejected += 1,
            Outcome::Unnamed(_) => self.unnamed += 1,
            Outcome::NotFinite(_) => self.not_finite += 1,
            Outcome::Panicked(_) => self.panicked += 1,
        }
        if changes.iter().all(|(_, c)| *c == Change::Plausible) {
            self.plausible += 1;
            self.plausible_valid += usize::from(outcome == Outcome::Valid);
        }
        if !matches!(outcome, Outcome::Valid | Outcome::Rejected)
            && self.failures.len() < KEPT_FAILURES
        {
            self.failures.push(Failure {
                index,
                changes: changes.iter().map(|(o, _)| o.to_string()).collect(),
                outcome,
            });
        }
        self
    }

    fn merge(mut self, other: Tally) -> Self {
        self.valid += other.valid;
        self.rejected += other.rejected;
        self.unnamed += other.unnamed;
        self.not_finite += other.not_finite;
        self.panicked += other.panicked;
        self.plausible += other.plausible;
        self.plausible_valid += other.plausible_valid;
        self.failures.extend(other.failures);
        self.failures.sort_by_key(|f| f.index);
        self.failures.truncate(KEPT_FAILURES);
        self
    }
}

/// Runs `cases` samples from `seed` in parallel; `progress` sees the count done.
pub fn run(cases: usize, seed: u64, progress: super::Progress) -> PropertyReport {
    let started = std::time::Instant::now();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tally = (0..cases as u64)
        .into_par_iter()
        .fold(Tally::default, |tally, index| {
            let changes = sample(seed, index);
            let outcome = check(&changes);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(1000) {
                progress("generated cases", n, cases);
            }
            tally.add(index, &changes, outcome)
        })
        .reduce(Tally::default, Tally::merge);
    PropertyReport {
        seed,
        cases,
        valid: tally.valid,
        rejected: tally.rejected,
        unnamed: tally.unnamed,
        not_finite: tally.not_finite,
        panicked: tally.panicked,
        plausible_cases: tally.plausible,
        plausible_valid_share: tally.plausible_valid as f64 / tally.plausible.max(1) as f64,
        failures: tally.failures,
        wall_s: started.elapsed().as_secs_f64(),
    }
}

/// The keys of `table` below the first level, as `a.b.c` (`gear1.tip.amount_um`).
fn dotted(table: &toml::Table, prefix: String, keys: &mut Vec<String>) {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) => dotted(inner, path, keys),
            _ if !prefix.is_empty() => keys.push(path),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(key: &str) -> Vec<(Override, Change)> {
        vec![(Override::set(key, 1.0), Change::OutOfRange)]
    }

    /// The check accepts a message that names the changed key precisely, or another key by
    /// its full path, and nothing vaguer.
    #[test]
    fn a_message_names_a_parameter_only_precisely() {
        let teeth = set("gear1.teeth");
        assert!(names_a_parameter("gear1.teeth = 3 is invalid", &teeth));
        assert!(names_a_parameter("12 | teeth = \"abc\"", &teeth));
        assert!(names_a_parameter("missing field `teeth`", &teeth));
        assert!(names_a_parameter("must be below tool.module_mm", &teeth));
        assert!(!names_a_parameter("solve failed", &teeth));
        assert!(!names_a_parameter("too many teeth", &teeth));
        let scene = set("scene[0].duration_s");
        assert!(names_a_parameter(
            "scene[0] (\"low-unmodified\").duration_s = -1 is invalid",
            &scene
        ));
        assert!(!names_a_parameter("the scene failed", &scene));
        assert!(!names_a_parameter(
            "scene[1] (\"x\").ramp_s is invalid",
            &scene
        ));
        let relief = set("relief_variant[1].gear1.tip.amount_um");
        assert!(names_a_parameter(
            "relief_variant \"tip20-root10\": gear1.tip.amount_um: -5 µm is out of range",
            &relief
        ));
        assert!(!names_a_parameter(
            "relief_variant \"tip20-root10\" is wrong",
            &relief
        ));
    }
}
