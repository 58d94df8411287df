//! Resources up front: the memory a model will take, checked against what the machine has before
//! the model is built, and `--force`, which lets a run go past the limits (memory here, the
//! explicit run's wall time in [`crate::study::fe::CostEstimate`]).
//!
//! The estimates count the large arrays a model is about to allocate, from their sizes, before
//! it does: a gear mesh and its stiffness triplets from the element and node counts
//! ([`crate::mesh::mesh_size`], without meshing), a sparse Cholesky factor from faer's own
//! symbolic analysis ([`crate::fe::assembly::AssembledStiffness`]), an explicit run's history
//! from its samples. They leave out the allocator's slack, the thread stacks and the small
//! arrays; `tests/memory.rs` holds them against the heap a counting allocator sees.
//!
//! The limit is [`LIMIT_SHARE`] of the memory available at the check (Linux: `MemAvailable`,
//! and the cgroup's `memory.max` less its `memory.current` where that is lower, as in a
//! container or a batch job), or `GEARDYN_MEMORY_LIMIT_MB` where set, the most one model may
//! take. Where neither can be read there is no memory check.

use std::sync::atomic::{AtomicBool, Ordering};

use thiserror::Error;

/// Share of the available memory a model may take: the rest is the slack of the allocator, the
/// outputs written after the model and what else runs on the machine.
pub const LIMIT_SHARE: f64 = 0.8;

/// The environment variable that sets the memory limit [MB] instead of the machine's.
pub const LIMIT_VARIABLE: &str = "GEARDYN_MEMORY_LIMIT_MB";

static FORCE: AtomicBool = AtomicBool::new(false);

/// `--force`: run what is above a limit anyway.
pub fn set_force(force: bool) {
    FORCE.store(force, Ordering::Relaxed);
}

/// Whether `--force` was given.
pub fn forced() -> bool {
    FORCE.load(Ordering::Relaxed)
}

/// The memory a model takes at its peak: named parts [bytes].
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct MemoryEstimate {
    pub parts: Vec<(String, f64)>,
}

impl MemoryEstimate {
    pub fn part(name: impl Into<String>, bytes: f64) -> Self {
        MemoryEstimate {
            parts: vec![(name.into(), bytes)],
        }
    }

    /// Both estimates' parts: what is held at once.
    pub fn and(mut self, other: MemoryEstimate) -> Self {
        self.parts.extend(other.parts);
        self
    }

    /// The larger of two phases that do not overlap.
    pub fn or(self, other: MemoryEstimate) -> Self {
        if other.total() > self.total() {
            other
        } else {
            self
        }
    }

    pub fn total(&self) -> f64 {
        self.parts.iter().map(|(_, b)| b).sum()
    }

    /// "about 130 MB (factor 60 MB, triplets 40 MB, …)", the largest parts first.
    pub fn describe(&self) -> String {
        let mut parts = self.parts.clone();
        parts.sort_by(|a, b| b.1.total_cmp(&a.1));
        let listed: Vec<String> = parts
            .iter()
            .take(3)
            .map(|(name, bytes)| format!("{name} {}", bytes_words(*bytes)))
            .collect();
        format!(
            "about {} ({})",
            bytes_words(self.total()),
            listed.join(", ")
        )
    }
}

/// Bytes as kB, MB or GB (decimal).
pub fn bytes_words(bytes: f64) -> String {
    if bytes < 1e6 {
        format!("{:.0} kB", bytes / 1e3)
    } else if bytes < 1e9 {
        format!("{:.0} MB", bytes / 1e6)
    } else {
        format!("{:.1} GB", bytes / 1e9)
    }
}

/// The memory limit and where it comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryLimit {
    pub bytes: f64,
    pub source: String,
}

/// The memory limit now: read at every check (a fraction of a millisecond), so what the
/// process already holds — the first gear body while the second is factorized — is not
/// available to the next model.
pub fn memory_limit() -> Option<MemoryLimit> {
    let variable = std::env::var(LIMIT_VARIABLE).ok();
    let read = |path: &str| std::fs::read_to_string(path).ok();
    limit_from(
        variable.as_deref(),
        read("/proc/meminfo").as_deref(),
        read("/sys/fs/cgroup/memory.max").as_deref(),
        read("/sys/fs/cgroup/memory.current").as_deref(),
    )
}

/// The limit from the variable's value, else [`LIMIT_SHARE`] of the available memory: the
/// lesser of /proc/meminfo's MemAvailable and the cgroup's memory.max − memory.current.
pub fn limit_from(
    variable: Option<&str>,
    meminfo: Option<&str>,
    cgroup_max: Option<&str>,
    cgroup_current: Option<&str>,
) -> Option<MemoryLimit> {
    if let Some(mb) = variable.and_then(|v| v.trim().parse::<f64>().ok()) {
        return Some(MemoryLimit {
            bytes: mb * 1e6,
            source: format!("{LIMIT_VARIABLE} = {mb}"),
        });
    }
    let available = meminfo.and_then(|text| {
        text.lines()
            .find_map(|line| line.strip_prefix("MemAvailable:"))
            .and_then(|rest| {
                rest.trim()
                    .trim_end_matches("kB")
                    .trim()
                    .parse::<f64>()
                    .ok()
            })
            .map(|kb| kb * 1024.0)
    });
    let cgroup = match (cgroup_max, cgroup_current) {
        (Some(max), Some(current)) => max
            .trim()
            .parse::<f64>()
            .ok()
            .zip(current.trim().parse::<f64>().ok())
            .map(|(max, current)| (max - current).max(0.0)),
        _ => None,
    };
    let (bytes, what) = match (available, cgroup) {
        (Some(a), Some(c)) if c < a => (c, "the cgroup's memory.max less its use"),
        (Some(a), _) => (a, "MemAvailable"),
        (None, Some(c)) => (c, "the cgroup's memory.max less its use"),
        (None, None) => return None,
    };
    Some(MemoryLimit {
        bytes: LIMIT_SHARE * bytes,
        source: format!(
            "{:.0} % of the {} available ({what})",
            LIMIT_SHARE * 100.0,
            bytes_words(bytes)
        ),
    })
}

/// A model whose memory estimate is above the limit.
#[derive(Debug, Clone, Error, PartialEq)]
#[error(
    "{what} would take {} of memory, above the limit of {} ({}): {remedy}; or add --force \
     to build it anyway, or set {LIMIT_VARIABLE}",
    estimate.describe(),
    bytes_words(limit.bytes),
    limit.source
)]
pub struct TooLarge {
    pub what: String,
    pub estimate: MemoryEstimate,
    pub limit: MemoryLimit,
    pub remedy: String,
}

/// Estimates from this size up are announced on the console before the model is built [bytes].
pub const ANNOUNCE_BYTES: f64 = 1e9;

/// Refuses `estimate` above the process's limit unless `--force`; announces it on stderr from
/// [`ANNOUNCE_BYTES`] up, with the limit.
pub fn check_memory(what: &str, estimate: &MemoryEstimate, remedy: &str) -> Result<(), TooLarge> {
    let limit = memory_limit();
    let checked = check_memory_against(limit.clone(), what, estimate, remedy);
    if checked.is_ok() && estimate.total() >= ANNOUNCE_BYTES {
        let against = limit.map_or("no limit known".to_string(), |l| {
            format!("limit {}: {}", bytes_words(l.bytes), l.source)
        });
        eprintln!("{what}: memory {} ({against})", estimate.describe());
    }
    checked
}

/// [`check_memory`] against a given limit.
pub fn check_memory_against(
    limit: Option<MemoryLimit>,
    what: &str,
    estimate: &MemoryEstimate,
    remedy: &str,
) -> Result<(), TooLarge> {
    match limit {
        Some(limit) if estimate.total() > limit.bytes && !forced() => Err(TooLarge {
            what: what.to_string(),
            estimate: estimate.clone(),
            limit,
            remedy: remedy.to_string(),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MEMINFO: &str =
        "MemTotal:       24000000 kB\nMemFree:         1000000 kB\nMemAvailable:   20000000 kB\n";

    #[test]
    fn the_limit_is_a_share_of_the_lesser_available_memory() {
        let machine = limit_from(None, Some(MEMINFO), Some("max\n"), Some("5000\n")).unwrap();
        assert_eq!(machine.bytes, 0.8 * 20_000_000.0 * 1024.0);
        assert!(
            machine.source.contains("MemAvailable"),
            "{}",
            machine.source
        );
        let job = limit_from(
            None,
            Some(MEMINFO),
            Some("4000000000\n"),
            Some("1000000000\n"),
        )
        .unwrap();
        assert_eq!(job.bytes, 0.8 * 3e9);
        assert!(job.source.contains("cgroup"), "{}", job.source);
        let set = limit_from(Some("250"), Some(MEMINFO), None, None).unwrap();
        assert_eq!(set.bytes, 250e6);
        assert_eq!(limit_from(None, None, None, None), None);
        // An unreadable variable falls back to the machine.
        assert_eq!(
            limit_from(Some("lots"), Some(MEMINFO), None, None)
                .unwrap()
                .bytes,
            machine.bytes
        );
    }

    #[test]
    fn an_estimate_above_the_limit_is_refused_with_its_parts_and_the_remedy() {
        let estimate = MemoryEstimate::part("factor", 3e9).and(MemoryEstimate::part("mesh", 1e8));
        assert_eq!(estimate.total(), 3.1e9);
        let limit = limit_from(Some("2000"), None, None, None);
        let error = check_memory_against(limit.clone(), "the LTCA bodies", &estimate, "coarsen")
            .unwrap_err()
            .to_string();
        for needed in [
            "the LTCA bodies",
            "3.1 GB",
            "factor 3.0 GB",
            "2.0 GB",
            "coarsen",
            "--force",
        ] {
            assert!(error.contains(needed), "{needed:?} missing from: {error}");
        }
        let small = MemoryEstimate::part("mesh", 1e8);
        assert!(check_memory_against(limit, "x", &small, "y").is_ok());
        assert!(check_memory_against(None, "x", &estimate, "y").is_ok());
        assert_eq!(
            MemoryEstimate::part("a", 1.0)
                .or(MemoryEstimate::part("b", 2.0))
                .parts[0]
                .0,
            "b"
        );
    }
}
