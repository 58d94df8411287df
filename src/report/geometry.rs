//! The geometry report: `summary.json`, the derived table, contact points and profile CSVs, and
//! a drawing of the pair (SVG, PNG). Units at this edge: mm, µm, degrees.

use crate::case::Case;
use crate::report::plot::{draw_svg_and_png, PairDrawing};
use crate::report::{OutputDir, ReportError};
use crate::study::geometry::{profile_rows, GeometrySummary, PROFILE_HEADER};

/// Writes every file of the geometry study.
pub fn write(out: OutputDir, case: &Case, summary: &GeometrySummary) -> Result<(), ReportError> {
    out.case(case)?;
    out.bytes("geometry.txt", summary.table().as_bytes())?;
    out.json("summary.json", summary)?;
    let pair = &case.pair;
    let rows = pair.contact_points.named().into_iter().map(|(name, s)| {
        let p = pair.loa_point(s);
        vec![
            name.to_string(),
            format!("{:.9}", s * 1e3),
            format!("{:.9}", pair.roll_angle_at(1, s).to_degrees()),
            format!("{:.9}", pair.roll_angle_at(2, s).to_degrees()),
            format!("{:.9}", p.x * 1e3),
            format!("{:.9}", p.y * 1e3),
        ]
    });
    out.csv(
        "contact_points.csv",
        &[
            "point",
            "distance_from_t1_mm",
            "roll_angle_gear1_deg",
            "roll_angle_gear2_deg",
            "x_mm",
            "y_mm",
        ],
        rows,
    )?;
    for variant in &case.relief_variants {
        for gear in 1..=2 {
            out.csv(
                &format!("profile_{}_gear{gear}.csv", variant.name),
                &PROFILE_HEADER,
                profile_rows(case, gear, &variant.modifications[gear - 1]),
            )?;
        }
    }
    // The drawing shows the first variant with relief, if any (relief is µm-scale: the CSVs
    // carry it).
    let variant = case
        .relief_variants
        .iter()
        .find(|v| !v.modifications.iter().all(|m| m.is_none()))
        .or(case.relief_variants.first());
    let modifications = variant.map(|v| v.modifications).unwrap_or_default();
    let title = format!(
        "{}: z = {}/{}, m = {} mm, contact ratio {:.4}{}",
        case.name(),
        pair.gears[0].teeth(),
        pair.gears[1].teeth(),
        case.file.tool.module_mm,
        pair.contact_ratio,
        variant
            .map(|v| format!(", relief \"{}\"", v.name))
            .unwrap_or_default()
    );
    draw_svg_and_png(
        &out.path("pair.svg"),
        &out.path("pair.png"),
        (1800, 900),
        &PairDrawing::new(pair, &modifications, title),
    )?;
    Ok(())
}
