//! Writes `geardyn validate quick`: checks.csv, checks.md and summary.json.

use super::{OutputDir, ReportError};
use crate::study::quick_validation::{CheckKind, QuickValidation};

/// Writes the checks; returns the Markdown table.
pub fn write(dir: OutputDir, result: &QuickValidation) -> Result<String, ReportError> {
    let rule = |kind: CheckKind, tolerance: f64| match kind {
        CheckKind::Absolute => format!("abs(value − reference) ≤ {tolerance:e}"),
        CheckKind::Relative => format!("abs(value / reference − 1) ≤ {tolerance:e}"),
        CheckKind::Below if tolerance > 0.0 => format!("value < (1 − {tolerance}) reference"),
        CheckKind::Below => "value < reference".to_string(),
    };
    dir.csv(
        "checks.csv",
        &[
            "study",
            "quantity",
            "value",
            "reference",
            "reference_source",
            "rule",
            "passed",
        ],
        result.checks.iter().map(|c| {
            vec![
                c.study.to_string(),
                c.quantity.clone(),
                format!("{:.9e}", c.value),
                format!("{:.9e}", c.reference),
                c.reference_source.clone(),
                rule(c.kind, c.tolerance),
                c.passed.to_string(),
            ]
        }),
    )?;
    let mut md = String::from(
        "| study | quantity | value | reference | against | rule | |\n|---|---|---|---|---|---|---|\n",
    );
    for c in &result.checks {
        md += &format!(
            "| {} | {} | {:.6} | {:.6} | {} | {} | {} |\n",
            c.study,
            c.quantity,
            c.value,
            c.reference,
            c.reference_source,
            rule(c.kind, c.tolerance),
            if c.passed { "ok" } else { "**FAILED**" }
        );
    }
    md += &format!(
        "\n{} passed, {} failed ({:.0} s)\n",
        result.passed, result.failed, result.wall_s
    );
    dir.bytes("checks.md", md.as_bytes())?;
    dir.json("summary.json", result)?;
    Ok(md)
}
