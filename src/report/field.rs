//! The stress field of the tooth with the largest fillet tension (`geardyn ltca`):
//! `stress_field.vtk` for ParaView (nodal displacement, stresses, max principal, von Mises) and
//! `stress_field.png` (max principal and von Mises on the mesh, the tooth upright). Units at
//! this edge: mm, µm, MPa.

use nalgebra::{Point2, Rotation2};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{draw_png, Drawing, PlotError};
use super::{vtk, OutputDir, ReportError};
use crate::case::Case;
use crate::study::ltca::PeakField;

/// Writes `stress_field.vtk` and `stress_field.png`.
pub fn write(out: OutputDir, case: &Case, peak: &PeakField) -> Result<(), ReportError> {
    let field = &peak.field;
    let title = format!(
        "{}: gear {} tooth {} at position {} (roll {:.2} deg), fillet tension {:.1} MPa",
        case.name(),
        peak.peak.gear,
        peak.peak.tooth,
        peak.peak.position,
        peak.peak.roll_angle_deg,
        peak.peak.tension_mpa
    );
    let mpa = |v: Vec<f64>| v.into_iter().map(|s| s * 1e-6).collect::<Vec<_>>();
    let component = |c: usize| field.stress.iter().map(|s| s[c] * 1e-6).collect();
    let text = vtk::field_to_vtk(
        &title,
        &field.nodes,
        &field.elements,
        &[
            ("max_principal_mpa", mpa(field.max_principal())),
            ("von_mises_mpa", mpa(field.von_mises())),
            ("sigma_xx_mpa", component(0)),
            ("sigma_yy_mpa", component(1)),
            ("tau_xy_mpa", component(2)),
        ],
        &[(
            "displacement_um",
            field
                .displacement
                .iter()
                .map(|u| [u.x * 1e6, u.y * 1e6])
                .collect(),
        )],
    );
    out.bytes("stress_field.vtk", text.as_bytes())?;
    let gear = case.pair.gear(peak.peak.gear);
    let drawing = FieldDrawing::new(peak, gear, title);
    Ok(draw_png(
        &out.path("stress_field.png"),
        (1800, 900),
        &drawing,
    )?)
}

/// Two panels, max principal and von Mises, each element filled by its nodes' mean.
struct FieldDrawing {
    title: String,
    /// Element polygons in mm, the tooth upright (its centre line on +y).
    polygons: Vec<Vec<(f64, f64)>>,
    /// Per element: mean max principal and mean von Mises [MPa].
    values: [Vec<f64>; 2],
    /// The view's radial range [mm] (its width follows from the panel's shape, equal scales).
    y_range: (f64, f64),
    /// The fillet node of the peak tension [mm].
    peak: Option<(f64, f64)>,
}

impl FieldDrawing {
    fn new(peak: &PeakField, gear: &crate::geometry::Gear, title: String) -> Self {
        let field = &peak.field;
        let upright = Rotation2::new(-(field.tooth as f64) * gear.angular_pitch());
        let mm = |p: &Point2<f64>| {
            let q = upright * p;
            (q.x * 1e3, q.y * 1e3)
        };
        let nodes: Vec<(f64, f64)> = field.nodes.iter().map(mm).collect();
        // The Q8 boundary: corner, mid-side, corner, ...
        let polygons = field
            .elements
            .iter()
            .map(|e| [0, 4, 1, 5, 2, 6, 3, 7].map(|k| nodes[e[k]]).to_vec())
            .collect();
        let per_element = |values: Vec<f64>| {
            field
                .elements
                .iter()
                .map(|e| e.iter().map(|&n| values[n]).sum::<f64>() / 8.0 * 1e-6)
                .collect()
        };
        let module = gear.module() * 1e3;
        let (root, tip) = (gear.root_radius * 1e3, gear.tip_radius * 1e3);
        let y_range = (root - 2.5 * module, tip + 0.5 * module);
        let principal = field.max_principal();
        let peak_node = field
            .mesh_node
            .iter()
            .position(|&n| n == peak.peak.tension_node);
        FieldDrawing {
            title,
            polygons,
            values: [per_element(principal), per_element(field.von_mises())],
            y_range,
            peak: peak_node.map(|i| nodes[i]),
        }
    }

    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        values: &[f64],
        caption: &str,
    ) -> Result<(), PlotError> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError {
            what: caption.to_string(),
            message: e.to_string(),
        };
        // Equal scales: the width from the plotting region's shape (less the label areas).
        let (width, height) = area.dim_in_pixel();
        let half_width = 0.5 * (self.y_range.1 - self.y_range.0) * (width as f64 - 74.0)
            / (height as f64 - 90.0);
        let x_range = (-half_width, half_width);
        // Whole elements only (plotters would clamp outside points onto the frame).
        let shown: Vec<usize> = (0..self.polygons.len())
            .filter(|&i| {
                self.polygons[i].iter().all(|&(x, y)| {
                    x >= x_range.0 && x <= x_range.1 && y >= self.y_range.0 && y <= self.y_range.1
                })
            })
            .collect();
        let (low, high) = shown
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |m, &i| {
                (m.0.min(values[i]), m.1.max(values[i]))
            });
        let span = (high - low).max(1e-12);
        // Blue (low) → green → yellow → red (high).
        let colour_of = |v: f64| {
            let t = ((v - low) / span).clamp(0.0, 1.0);
            HSLColor(0.66 * (1.0 - t), 0.9, 0.3 + 0.25 * t)
        };
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d(x_range.0..x_range.1, self.y_range.0..self.y_range.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("across the tooth [mm]")
            .y_desc("radius along the tooth's centre line [mm]")
            .draw()
            .map_err(err)?;
        chart
            .draw_series(
                shown.iter().map(|&i| {
                    Polygon::new(self.polygons[i].clone(), colour_of(values[i]).filled())
                }),
            )
            .map_err(err)?;
        if let Some(peak) = self.peak {
            chart
                .draw_series([Cross::new(peak, 8, BLACK.stroke_width(3))])
                .map_err(err)?
                .label("largest fillet tension of the cycle")
                .legend(|(x, y)| Cross::new((x + 8, y), 6, BLACK.stroke_width(2)));
        }
        // The scale: six swatches from the lowest to the highest shown value.
        for k in (0..6).rev() {
            let value = low + span * k as f64 / 5.0;
            let colour = colour_of(value);
            chart
                .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())
                .map_err(err)?
                .label(format!("{value:.1} MPa"))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 18, y + 6)], colour.filled())
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

impl Drawing for FieldDrawing {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError {
            what: self.title.clone(),
            message: e.to_string(),
        };
        root.fill(&WHITE).map_err(err)?;
        let (width, _) = root.dim_in_pixel();
        let titled = root.titled(&self.title, ("sans-serif", 20)).map_err(err)?;
        let (left, right) = titled.split_horizontally(width / 2);
        self.panel(&left, &self.values[0], "max principal stress [MPa]")?;
        self.panel(&right, &self.values[1], "von Mises stress [MPa]")
    }
}
