//! The IO edge: output folders, atomic file writes, JSON summaries, CSV tables and drawings.
//!
//! Every file is written to a temporary name in its folder and renamed into place, so a reader
//! (or a crash) never sees half a file.

pub mod compare;
pub mod fe;
pub mod field;
pub mod geometry;
pub mod ltca;
pub mod lumped;
pub mod mesh;
pub mod optimize;
pub mod pairs;
pub mod plot;
pub mod quick_validation;
pub mod run;
pub mod stiffness_csv;
pub mod vtk;

use std::io::Write;
use std::path::{Path, PathBuf};

/// A file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
}

/// Whether a summary key holds a measurement of the run's cost (wall time, time per
/// element-step, threads used) rather than a result. These are the only values that change
/// between two runs of the same case and command, on any number of threads; every key that
/// holds one contains `wall` (`wall_s`, `stiffness_wall_s`, `wall_ns_per_element_step`, ...).
pub fn is_timing_key(key: &str) -> bool {
    key.contains("wall")
}

/// The folder one command writes into; every file is written atomically and a failure names it.
#[derive(Debug, Clone, Copy)]
pub struct OutputDir<'a>(pub &'a Path);

impl OutputDir<'_> {
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn named(&self, name: &str) -> impl Fn(std::io::Error) -> ReportError + '_ {
        let path = self.path(name).display().to_string();
        move |source| ReportError::Io {
            path: path.clone(),
            source,
        }
    }

    pub fn bytes(&self, name: &str, bytes: &[u8]) -> Result<(), ReportError> {
        write_atomic(&self.path(name), bytes).map_err(self.named(name))
    }

    pub fn json<T: serde::Serialize>(&self, name: &str, value: &T) -> Result<(), ReportError> {
        write_json(&self.path(name), value).map_err(self.named(name))
    }

    pub fn csv(
        &self,
        name: &str,
        header: &[&str],
        rows: impl IntoIterator<Item = Vec<String>>,
    ) -> Result<(), ReportError> {
        write_csv(&self.path(name), header, rows).map_err(self.named(name))
    }

    /// `stem.svg` and `stem.png` of a chart.
    pub fn chart(&self, stem: &str, picture: &impl plot::Drawing) -> Result<(), ReportError> {
        Ok(plot::save_chart(self.0, stem, picture)?)
    }

    /// Removes file `name` if it is there (a checkpoint a finished run no longer needs).
    pub fn remove(&self, name: &str) -> Result<(), ReportError> {
        match std::fs::remove_file(self.path(name)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(self.named(name)(e)),
            _ => Ok(()),
        }
    }

    /// The effective case (after overrides), so the run can be repeated from its folder.
    pub fn case(&self, case: &crate::case::Case) -> Result<(), ReportError> {
        self.bytes("case.toml", case.text.as_bytes())
    }
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, then
/// renamed over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_sibling(path);
    {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
    }
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// A temporary name next to `path` that keeps its extension (plot backends pick the format
/// from it): `dir/.name.tmp.ext`.
pub fn temporary_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (stem, ext) = match name.rsplit_once('.') {
        Some((s, e)) => (s.to_string(), format!(".{e}")),
        None => (name.clone(), String::new()),
    };
    path.with_file_name(format!(".{stem}.tmp{ext}"))
}

/// Serialises `value` as pretty JSON into `path`, atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> std::io::Result<()> {
    let mut text = serde_json::to_string_pretty(value).map_err(std::io::Error::other)?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Writes a CSV file atomically from a header and rows of already formatted fields.
pub fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<String>>,
) -> std::io::Result<()> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(header).map_err(std::io::Error::other)?;
    for row in rows {
        writer.write_record(&row).map_err(std::io::Error::other)?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| std::io::Error::other(e.to_string()))?;
    write_atomic(path, &bytes)
}

/// A fresh output folder `base/<command>-<case>-NNN` (the first unused number), created.
pub fn fresh_output_dir(base: &Path, command: &str, case_name: &str) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(base)?;
    for n in 1..100_000 {
        let dir = base.join(format!("{command}-{case_name}-{n:03}"));
        match std::fs::create_dir(&dir) {
            Ok(()) => return Ok(dir),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other(format!(
        "no free output folder name under {}",
        base.display()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("geardyn-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("summary.json");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        assert!(!temporary_sibling(&path).exists());
        assert_eq!(
            temporary_sibling(&path).file_name().unwrap(),
            ".summary.tmp.json"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn fresh_output_dirs_do_not_collide() {
        let base = std::env::temp_dir().join(format!("geardyn-out-{}", std::process::id()));
        let a = fresh_output_dir(&base, "geometry", "x").unwrap();
        let b = fresh_output_dir(&base, "geometry", "x").unwrap();
        assert_ne!(a, b);
        std::fs::remove_dir_all(&base).unwrap();
    }
}
