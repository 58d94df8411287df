//! The stiffness table file that every source writes and the lumped model reads: CSV with
//! columns `roll_angle_deg` (driver roll angle over one mesh period), `mesh_stiffness_n_per_m`,
//! and optionally `unloaded_te_um` (unloaded transmission error along the line of action).
//! Other columns are ignored, so an `ltca_<variant>.csv` is itself a valid stiffness file.

use std::path::Path;

use crate::lumped::PeriodicTable;

/// Writes the stiffness file: roll angles [rad], stiffness [N/m], unloaded TE [m].
pub fn write_stiffness_csv(
    path: &Path,
    roll_angles: &[f64],
    stiffness: &[f64],
    unloaded_te: &[f64],
) -> std::io::Result<()> {
    super::write_csv(
        path,
        &["roll_angle_deg", "mesh_stiffness_n_per_m", "unloaded_te_um"],
        (0..roll_angles.len()).map(|i| {
            vec![
                format!("{:.9}", roll_angles[i].to_degrees()),
                format!("{:.9e}", stiffness[i]),
                format!("{:.9}", unloaded_te[i] * 1e6),
            ]
        }),
    )
}

/// Reads a stiffness file into periodic tables of the mesh period `period` [rad]:
/// (k(θ) [N/m], e(θ) [m], zero when the column is absent). The message says what is wrong.
pub fn read_stiffness_csv(
    path: &Path,
    period: f64,
) -> Result<(PeriodicTable, PeriodicTable), String> {
    let shown = path.display();
    let mut reader =
        csv::Reader::from_path(path).map_err(|e| format!("cannot read {shown}: {e}"))?;
    let header = reader
        .headers()
        .map_err(|e| format!("{shown}: no header row: {e}"))?
        .clone();
    let column = |name: &str| header.iter().position(|h| h.trim() == name);
    let (Some(angle_col), Some(k_col)) =
        (column("roll_angle_deg"), column("mesh_stiffness_n_per_m"))
    else {
        return Err(format!(
            "{shown}: needs the columns roll_angle_deg and mesh_stiffness_n_per_m (found: {})",
            header.iter().collect::<Vec<_>>().join(", ")
        ));
    };
    let te_col = column("unloaded_te_um");
    let (mut angles, mut k, mut te) = (Vec::new(), Vec::new(), Vec::new());
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(|e| format!("{shown}: {e}"))?;
        let line = row + 2;
        let number = |col: usize, name: &str| -> Result<f64, String> {
            let text = record.get(col).unwrap_or("").trim();
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    format!("{shown} line {line}: {name} = {text:?} is not a finite number")
                })
        };
        angles.push(number(angle_col, "roll_angle_deg")?.to_radians());
        let stiffness = number(k_col, "mesh_stiffness_n_per_m")?;
        if !(stiffness > 0.0) {
            return Err(format!(
                "{shown} line {line}: mesh_stiffness_n_per_m = {stiffness} must be > 0 (teeth always in contact; separation is the model's job)"
            ));
        }
        k.push(stiffness);
        te.push(match te_col {
            Some(c) => number(c, "unloaded_te_um")? * 1e-6,
            None => 0.0,
        });
    }
    let table = |values: &[f64]| {
        PeriodicTable::from_samples(period, &angles, values).map_err(|e| {
            format!(
                "{shown}: {e} (the mesh period is {:.6} deg of driver roll angle)",
                period.to_degrees()
            )
        })
    };
    Ok((table(&k)?, table(&te)?))
}
