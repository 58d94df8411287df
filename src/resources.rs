//! Resources up front: the memory a model will take, checked against a limit before the model
//! is built, and `--force`, which lets a run go past the limits (memory here, the explicit
//! run's wall time in [`crate::study::fe::CostEstimate`]).
//!
//! The estimates count the large arrays a model is about to allocate, from their sizes, before
//! it does: a gear mesh, its stiffness triplets and K from the element and node counts
//! ([`crate::mesh::mesh_size`], without meshing), a sparse Cholesky factor from faer's own
//! symbolic analysis ([`crate::fe::assembly::AssembledStiffness`]), an explicit run's history
//! from its samples. They leave out the allocator's slack, the thread stacks and the small
//! arrays; `tests/memory.rs` holds them against the heap a counting allocator sees.
//!
//! Like the stop request ([`crate::interrupt`]), the limit is the process's: the binary reads
//! the machine once at its start ([`machine_limit`]) and sets it ([`set_memory_limit`]); the
//! kernels compare their estimates with it and do no IO. Without a limit set (the library in
//! tests, benches, another program) nothing is refused.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::RwLock;

use thiserror::Error;

/// Share of the available memory a model may take: the rest is the slack of the allocator, the
/// outputs written after the model and what else runs on the machine.
pub const LIMIT_SHARE: f64 = 0.8;

/// The environment variable that sets the memory limit [MB] instead of the machine's.
pub const LIMIT_VARIABLE: &str = "GEARDYN_MEMORY_LIMIT_MB";

/// Estimates from this size up are announced before the model is built [bytes].
pub const ANNOUNCE_BYTES: f64 = 1e9;

static FORCE: AtomicBool = AtomicBool::new(false);
static LIMIT: RwLock<Option<MemoryLimit>> = RwLock::new(None);
static ANNOUNCER: RwLock<Option<fn(&str)>> = RwLock::new(None);

/// `--force`: run what is above a limit anyway.
pub fn set_force(force: bool) {
    FORCE.store(force, Ordering::Relaxed);
}

/// Whether `--force` was given.
pub fn forced() -> bool {
    FORCE.load(Ordering::Relaxed)
}

/// Sets the process's memory limit (None: no check).
pub fn set_memory_limit(limit: Option<MemoryLimit>) {
    *LIMIT.write().unwrap_or_else(|e| e.into_inner()) = limit;
}

/// The process's memory limit, as set.
pub fn memory_limit() -> Option<MemoryLimit> {
    LIMIT.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Where estimates of [`ANNOUNCE_BYTES`] and more that pass the check are told (the binary:
/// its console).
pub fn set_announcer(announce: fn(&str)) {
    *ANNOUNCER.write().unwrap_or_else(|e| e.into_inner()) = Some(announce);
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

impl MemoryLimit {
    /// Each one's share when `runs` models are built and held side by side (the local
    /// executor's runs): the limit over `runs`, with its source saying so.
    pub fn shared(&self, runs: usize) -> MemoryLimit {
        if runs <= 1 {
            return self.clone();
        }
        MemoryLimit {
            bytes: self.bytes / runs as f64,
            source: format!(
                "{} of {}, {}; shared by {runs} explicit runs side by side: --jobs 1 gives one \
                 run the whole",
                match runs {
                    2 => "a half".to_string(),
                    n => format!("1/{n}"),
                },
                bytes_words(self.bytes),
                self.source
            ),
        }
    }
}

/// One level of the process's memory cgroup, as read: its limit, its use and its statistics.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CgroupLevel {
    /// cgroup v2 `memory.max` ("max": none) or v1 `memory.limit_in_bytes`.
    pub limit: Option<String>,
    /// v2 `memory.current` or v1 `memory.usage_in_bytes`.
    pub usage: Option<String>,
    /// `memory.stat`: its page cache (v2 `file`, v1 `total_cache`), which the kernel reclaims
    /// before it refuses memory, is not counted as used.
    pub stat: Option<String>,
}

impl CgroupLevel {
    /// limit − (usage − page cache) [bytes], where the level has a limit.
    fn headroom(&self) -> Option<f64> {
        let number = |text: &Option<String>| text.as_deref()?.trim().parse::<f64>().ok();
        // v1 writes "no limit" as a number near 2⁶³.
        let limit = number(&self.limit).filter(|l| *l < 1e18)?;
        let cache = self.stat.as_deref().and_then(|stat| {
            stat.lines().find_map(|line| {
                let (key, value) = line.split_once(' ')?;
                matches!(key, "file" | "total_cache")
                    .then(|| value.trim().parse::<f64>().ok())
                    .flatten()
            })
        });
        let used = (number(&self.usage)? - cache.unwrap_or(0.0)).max(0.0);
        Some((limit - used).max(0.0))
    }
}

/// The machine's limit for this process, read now: `GEARDYN_MEMORY_LIMIT_MB` where set, else
/// [`LIMIT_SHARE`] of the lesser of /proc/meminfo's `MemAvailable` and the headroom of every
/// level of the process's memory cgroup (v2, or v1's memory controller), from its own group up
/// to the root — a container's or a batch job's limit. Linux only; elsewhere None.
pub fn machine_limit() -> Option<MemoryLimit> {
    let read = |path: String| std::fs::read_to_string(path).ok();
    let mut levels = Vec::new();
    if let Some(cgroups) = read("/proc/self/cgroup".into()) {
        let v2 = cgroups.lines().find_map(|l| l.strip_prefix("0::"));
        let v1 = cgroups.lines().find_map(|l| {
            let (_, rest) = l.split_once(':')?;
            let (controllers, path) = rest.split_once(':')?;
            controllers
                .split(',')
                .any(|c| c == "memory")
                .then_some(path)
        });
        let (root, path, files) = match (v1, v2) {
            (Some(path), _) => (
                "/sys/fs/cgroup/memory",
                path,
                ["memory.limit_in_bytes", "memory.usage_in_bytes"],
            ),
            (None, Some(path)) => ("/sys/fs/cgroup", path, ["memory.max", "memory.current"]),
            (None, None) => ("", "", ["", ""]),
        };
        if !root.is_empty() {
            let path = path.trim_end().trim_end_matches('/');
            let mut dir = std::path::PathBuf::from(format!("{root}{path}"));
            loop {
                let file = |name: &str| read(dir.join(name).display().to_string());
                levels.push(CgroupLevel {
                    limit: file(files[0]),
                    usage: file(files[1]),
                    stat: file("memory.stat"),
                });
                if dir.as_os_str().len() <= root.len() || !dir.pop() {
                    break;
                }
            }
        }
    }
    limit_from(
        std::env::var(LIMIT_VARIABLE).ok().as_deref(),
        read("/proc/meminfo".into()).as_deref(),
        &levels,
    )
}

/// The limit from the variable's value, else [`LIMIT_SHARE`] of the least of /proc/meminfo's
/// `MemAvailable` and the cgroup levels' headroom.
pub fn limit_from(
    variable: Option<&str>,
    meminfo: Option<&str>,
    cgroup: &[CgroupLevel],
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
    let headroom = cgroup
        .iter()
        .filter_map(CgroupLevel::headroom)
        .reduce(f64::min);
    let (bytes, what) = match (available, headroom) {
        (Some(a), Some(c)) if c < a => (c, "the cgroup's limit less its use"),
        (Some(a), _) => (a, "MemAvailable"),
        (None, Some(c)) => (c, "the cgroup's limit less its use"),
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

/// Refuses `estimate` above the process's limit unless `--force`; hands an estimate of
/// [`ANNOUNCE_BYTES`] or more that passes to the announcer, with the limit.
pub fn check_memory(what: &str, estimate: &MemoryEstimate, remedy: &str) -> Result<(), TooLarge> {
    let limit = memory_limit();
    let checked = check_memory_against(limit.clone(), what, estimate, remedy);
    let announcer = *ANNOUNCER.read().unwrap_or_else(|e| e.into_inner());
    if let (Ok(()), Some(announce)) = (&checked, announcer) {
        if estimate.total() >= ANNOUNCE_BYTES {
            let against = limit.map_or("no limit set".to_string(), |l| {
                format!("limit {}: {}", bytes_words(l.bytes), l.source)
            });
            announce(&format!(
                "{what}: memory {} ({against})",
                estimate.describe()
            ));
        }
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

    /// Runs side by side each get their share, and a refusal says how to get the whole.
    #[test]
    fn a_shared_limit_is_each_runs_share() {
        let whole = MemoryLimit {
            bytes: 8e9,
            source: "GEARDYN_MEMORY_LIMIT_MB = 8000".into(),
        };
        assert_eq!(whole.shared(1), whole);
        let half = whole.shared(2);
        assert_eq!(half.bytes, 4e9);
        assert!(half.source.contains("a half") && half.source.contains("--jobs 1"));
        assert_eq!(whole.shared(4).bytes, 2e9);
        let refused = check_memory_against(
            Some(half),
            "the run",
            &MemoryEstimate::part("history", 5e9),
            "shorten it",
        )
        .unwrap_err();
        assert!(refused.to_string().contains("--jobs 1"), "{refused}");
    }

    fn level(limit: &str, usage: &str, stat: &str) -> CgroupLevel {
        CgroupLevel {
            limit: Some(limit.into()),
            usage: Some(usage.into()),
            stat: Some(stat.into()),
        }
    }

    #[test]
    fn the_limit_is_a_share_of_the_least_headroom() {
        let unlimited = [level("max\n", "5000\n", "anon 4000\nfile 1000\n")];
        let machine = limit_from(None, Some(MEMINFO), &unlimited).unwrap();
        assert_eq!(machine.bytes, 0.8 * 20_000_000.0 * 1024.0);
        assert!(
            machine.source.contains("MemAvailable"),
            "{}",
            machine.source
        );
        // A 4 GB job using 3 GB, 2.5 GB of it page cache (a build's files): 3.5 GB of headroom,
        // not 1 GB. Its parent, unlimited; v1 writes that as a number near 2⁶³.
        let job = [
            level(
                "4000000000\n",
                "3000000000\n",
                "anon 500000000\nfile 2500000000\n",
            ),
            level("9223372036854771712\n", "1\n", "total_cache 0\n"),
        ];
        let limited = limit_from(None, Some(MEMINFO), &job).unwrap();
        assert_eq!(limited.bytes, 0.8 * 3.5e9);
        assert!(limited.source.contains("cgroup"), "{}", limited.source);
        // The tighter of two levels: a parent with 2 GB left.
        let nested = [
            job[0].clone(),
            level("6000000000\n", "4000000000\n", "file 0\n"),
        ];
        assert_eq!(
            limit_from(None, Some(MEMINFO), &nested).unwrap().bytes,
            0.8 * 2e9
        );
        let set = limit_from(Some("250"), Some(MEMINFO), &job).unwrap();
        assert_eq!(set.bytes, 250e6);
        assert_eq!(limit_from(None, None, &[]), None);
        // An unreadable variable falls back to the machine.
        assert_eq!(
            limit_from(Some("lots"), Some(MEMINFO), &[]).unwrap().bytes,
            machine.bytes
        );
    }

    #[test]
    fn an_estimate_above_the_limit_is_refused_with_its_parts_and_the_remedy() {
        let estimate = MemoryEstimate::part("factor", 3e9).and(MemoryEstimate::part("mesh", 1e8));
        assert_eq!(estimate.total(), 3.1e9);
        let limit = limit_from(Some("2000"), None, &[]);
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
