//! The stiffness file at the IO edge: [`MeshStiffness`] written atomically and read from a path
//! (the format itself is [`crate::stiffness::mesh`]'s).

use std::path::Path;

use crate::stiffness::MeshStiffness;

/// Writes `stiffness` in the stiffness file format, atomically.
pub fn write_stiffness_csv(path: &Path, stiffness: &MeshStiffness) -> std::io::Result<()> {
    super::write_atomic(path, stiffness.to_csv().as_bytes())
}

/// Reads a stiffness file for a mesh of period `period` [rad] (driver roll angle); its source
/// reads `csv (<path>)`. The message says what is wrong.
pub fn read_stiffness_csv(path: &Path, period: f64) -> Result<MeshStiffness, String> {
    let shown = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {shown}: {e}"))?;
    MeshStiffness::from_csv(file, &shown, period, format!("csv ({shown})"))
}
