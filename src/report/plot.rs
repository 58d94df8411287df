//! Drawings with plotters, to SVG and PNG, with an embedded font (DejaVu Sans, licence in
//! `data/fonts/`) so no system font library is needed.

use std::path::Path;
use std::sync::Once;

use nalgebra::Point2;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::geometry::{FlankModification, GearPair, OutlineResolution};

static FONT: &[u8] = include_bytes!("../../data/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded font as "sans-serif" (once per process).
pub fn register_font() {
    REGISTER.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans font is a valid TTF"));
    });
}

/// A drawing failed (backend or file error), with what was being drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw {what}: {message}")]
pub struct PlotError {
    pub what: String,
    pub message: String,
}

fn plot_err<E: std::fmt::Display>(what: &str) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError {
        what: what.into(),
        message: e.to_string(),
    }
}

/// A picture that can be drawn on any plotters backend.
pub trait Drawing {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), PlotError>;
}

/// Draws a picture to a PNG file (written atomically).
pub fn draw_png(png: &Path, size: (u32, u32), picture: &impl Drawing) -> Result<(), PlotError> {
    register_font();
    let what = png.display().to_string();
    let tmp = super::temporary_sibling(png);
    {
        let area = BitMapBackend::new(&tmp, size).into_drawing_area();
        picture.draw(&area)?;
        area.present().map_err(plot_err(&what))?;
    }
    std::fs::rename(&tmp, png).map_err(plot_err(&what))
}

/// Size of the line charts and colour maps.
pub const CHART_SIZE: (u32, u32) = (1200, 700);

/// Writes `dir/stem.svg` and `dir/stem.png` of a chart at [`CHART_SIZE`].
pub fn save_chart(dir: &Path, stem: &str, picture: &impl Drawing) -> Result<(), PlotError> {
    draw_svg_and_png(
        &dir.join(format!("{stem}.svg")),
        &dir.join(format!("{stem}.png")),
        CHART_SIZE,
        picture,
    )
}

/// Draws the same picture to an SVG and a PNG file (each written atomically).
pub fn draw_svg_and_png(
    svg: &Path,
    png: &Path,
    size: (u32, u32),
    picture: &impl Drawing,
) -> Result<(), PlotError> {
    register_font();
    let what = svg.display().to_string();
    let mut text = String::new();
    {
        let area = SVGBackend::with_string(&mut text, size).into_drawing_area();
        picture.draw(&area)?;
        area.present().map_err(plot_err(&what))?;
    }
    super::write_atomic(svg, text.as_bytes()).map_err(plot_err(&what))?;
    draw_png(png, size, picture)
}

/// Everything the pair drawing shows, in mm, in the placement frame (gear 1 at the origin).
pub struct PairDrawing {
    pub outlines: [Vec<(f64, f64)>; 2],
    pub centres: [(f64, f64); 2],
    pub base_radii: [f64; 2],
    pub pitch_radii: [f64; 2],
    pub tip_radii: [f64; 2],
    pub bore_radii: [f64; 2],
    pub line_of_action: [(f64, f64); 2],
    pub contact_points: Vec<(&'static str, (f64, f64))>,
    pub title: String,
}

impl PairDrawing {
    pub fn new(pair: &GearPair, modifications: &[FlankModification; 2], title: String) -> Self {
        let placement = pair.mesh_placement();
        let mm = |p: Point2<f64>| (p.x * 1e3, p.y * 1e3);
        let outline = |i: usize| {
            let mut points: Vec<(f64, f64)> = pair.gears[i]
                .gear_outline(&modifications[i], OutlineResolution::default())
                .iter()
                .map(|p| mm(placement[i].to_global(p)))
                .collect();
            points.push(points[0]);
            points
        };
        let c = pair.contact_points;
        PairDrawing {
            outlines: [outline(0), outline(1)],
            centres: [mm(placement[0].centre), mm(placement[1].centre)],
            base_radii: [
                pair.gears[0].base_radius * 1e3,
                pair.gears[1].base_radius * 1e3,
            ],
            pitch_radii: [
                pair.working_pitch_radii[0] * 1e3,
                pair.working_pitch_radii[1] * 1e3,
            ],
            tip_radii: [
                pair.gears[0].tip_radius * 1e3,
                pair.gears[1].tip_radius * 1e3,
            ],
            bore_radii: [
                pair.gears[0].spec.bore_radius * 1e3,
                pair.gears[1].spec.bore_radius * 1e3,
            ],
            line_of_action: [
                mm(pair.loa_point(0.0)),
                mm(pair.loa_point(pair.line_of_action_length)),
            ],
            contact_points: c
                .named()
                .iter()
                .map(|(n, s)| (*n, mm(pair.loa_point(*s))))
                .collect(),
            title,
        }
    }

    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        xr: (f64, f64),
        yr: (f64, f64),
        caption: &str,
        line_width: u32,
        labels: bool,
    ) -> Result<(), PlotError> {
        let inside = |p: &(f64, f64)| p.0 >= xr.0 && p.0 <= xr.1 && p.1 >= yr.0 && p.1 <= yr.1;
        let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>("the meshing pair");
        let mut chart = panel_chart(area, xr, yr, caption).map_err(&err)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(&err)?;
        let grey = RGBColor(150, 150, 150);
        let colours = [RGBColor(31, 90, 180), RGBColor(200, 50, 40)];
        #[allow(clippy::needless_range_loop)] // i indexes five parallel per-gear arrays
        for i in 0..2 {
            let centre = self.centres[i];
            for (radius, style) in [
                (self.base_radii[i], ShapeStyle::from(&grey).stroke_width(1)),
                (
                    self.pitch_radii[i],
                    ShapeStyle::from(&grey.mix(0.6)).stroke_width(1),
                ),
                (
                    self.bore_radii[i],
                    ShapeStyle::from(&colours[i]).stroke_width(1),
                ),
            ] {
                for run in inside_runs(&circle(centre, radius), &inside) {
                    chart
                        .draw_series(DashedLineSeries::new(run, 6, 4, style))
                        .map_err(&err)?;
                }
            }
            let style = ShapeStyle::from(&colours[i]).stroke_width(line_width);
            let runs = inside_runs(&self.outlines[i], &inside);
            for (k, run) in runs.into_iter().enumerate() {
                let series = chart
                    .draw_series(LineSeries::new(run, style))
                    .map_err(&err)?;
                if k == 0 {
                    let name = if i == 0 {
                        "gear 1 (driver)"
                    } else {
                        "gear 2 (driven)"
                    };
                    let colour = colours[i];
                    series
                        .label(name)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
                }
            }
            if inside(&centre) {
                let cross = Cross::new(centre, 5, ShapeStyle::from(&BLACK));
                chart.draw_series(std::iter::once(cross)).map_err(&err)?;
            }
        }
        let green = RGBColor(20, 140, 60);
        chart
            .draw_series(LineSeries::new(
                self.line_of_action.iter().copied(),
                green.stroke_width(2),
            ))
            .map_err(&err)?
            .label("line of action T1-T2")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], green));
        for (k, (name, p)) in self.contact_points.iter().enumerate() {
            chart
                .draw_series(std::iter::once(Circle::new(
                    *p,
                    5,
                    ShapeStyle::from(&BLACK).filled(),
                )))
                .map_err(&err)?;
            if !labels {
                continue;
            }
            // Labels alternate sides of the line of action so neighbours do not overlap.
            let offset = if k % 2 == 0 { (10, -6) } else { (-62, -6) };
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at(*p)
                        + Text::new(name.to_string(), offset, ("sans-serif", 15).into_font()),
                ))
                .map_err(&err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(&err)?;
        Ok(())
    }
}

/// The Cartesian chart of one panel of a two-panel drawing, in mm.
type PanelChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn panel_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    xr: (f64, f64),
    yr: (f64, f64),
    caption: &str,
) -> Result<PanelChart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(45)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
}

/// A left and a right panel.
type Panels<DB> = (DrawingArea<DB, Shift>, DrawingArea<DB, Shift>);

/// A white picture with a title, split into a left and a right panel.
fn two_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<Panels<DB>, PlotError> {
    let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>(title);
    root.fill(&WHITE).map_err(&err)?;
    let (width, _) = root.dim_in_pixel();
    let titled = root.titled(title, ("sans-serif", 22)).map_err(&err)?;
    Ok(titled.split_horizontally(width / 2))
}

impl Drawing for PairDrawing {
    /// Two panels: the whole pair, and the mesh zone around the path of contact.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (left, right) = two_panels(root, &self.title)?;

        // Whole pair: equal scales, both tip circles inside.
        let (c1, c2) = (self.centres[0], self.centres[1]);
        let x0 = c1.0 - self.tip_radii[0] * 1.08;
        let x1 = c2.0 + self.tip_radii[1] * 1.08;
        let half_height = 0.5 * (x1 - x0) * aspect(&left);
        self.panel(
            &left,
            (x0, x1),
            (-half_height, half_height),
            "meshing pair [mm]",
            1,
            false,
        )?;

        // Mesh zone: the path of contact with a margin, centred on the pitch point.
        let a = self.contact_points[0].1;
        let e = self.contact_points[4].1;
        let pitch = self.contact_points[2].1;
        let span = ((e.0 - a.0).hypot(e.1 - a.1)) * 0.85;
        let half_height = span * aspect(&right);
        self.panel(
            &right,
            (pitch.0 - span, pitch.0 + span),
            (pitch.1 - half_height, pitch.1 + half_height),
            "mesh zone: line of action and contact points [mm]",
            2,
            true,
        )
    }
}

/// Height/width of the plotting region of an area (approximately, before margins).
fn aspect<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> f64 {
    let (w, h) = area.dim_in_pixel();
    (h as f64 - 70.0) / (w as f64 - 60.0)
}

/// The maximal runs of consecutive points inside the plotted window (plotters would otherwise
/// clamp outside points onto the frame and draw along it).
fn inside_runs(
    points: &[(f64, f64)],
    inside: &dyn Fn(&(f64, f64)) -> bool,
) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current = Vec::new();
    for p in points {
        if inside(p) {
            current.push(*p);
        } else if !current.is_empty() {
            runs.push(std::mem::take(&mut current));
        }
    }
    if !current.is_empty() {
        runs.push(current);
    }
    runs
}

fn circle(centre: (f64, f64), radius: f64) -> Vec<(f64, f64)> {
    (0..=360)
        .map(|k| {
            let t = (k as f64).to_radians();
            (centre.0 + radius * t.cos(), centre.1 + radius * t.sin())
        })
        .collect()
}

/// A gear mesh: the whole gear, and a zoom on the fine teeth (element edges follow the
/// quadratic edges through their mid-side nodes).
pub struct MeshDrawing {
    /// Element edges as 3-point polylines (corner, mid-side, corner), mm.
    pub edges: Vec<[(f64, f64); 3]>,
    pub fine_edges: Vec<bool>,
    pub zoom: ((f64, f64), (f64, f64)),
    pub extent: f64,
    pub title: String,
}

impl MeshDrawing {
    pub fn new(
        mesh: &crate::mesh::GearMesh,
        zoom_centre: Point2<f64>,
        zoom_half_width: f64,
        title: String,
    ) -> Self {
        let mut edges = Vec::with_capacity(4 * mesh.elements.len());
        let mut fine_edges = Vec::with_capacity(4 * mesh.elements.len());
        let mm = |i: usize| (mesh.nodes[i].x * 1e3, mesh.nodes[i].y * 1e3);
        for (e, fine) in mesh.elements.iter().zip(&mesh.element_fine) {
            for (a, m, b) in [(0, 4, 1), (1, 5, 2), (2, 6, 3), (3, 7, 0)] {
                edges.push([mm(e[a]), mm(e[m]), mm(e[b])]);
                fine_edges.push(*fine);
            }
        }
        let extent = mesh
            .nodes
            .iter()
            .map(|p| p.coords.norm())
            .fold(0.0, f64::max)
            * 1e3
            * 1.04;
        let (cx, cy, h) = (
            zoom_centre.x * 1e3,
            zoom_centre.y * 1e3,
            zoom_half_width * 1e3,
        );
        MeshDrawing {
            edges,
            fine_edges,
            zoom: ((cx - h, cx + h), (cy - h, cy + h)),
            extent,
            title,
        }
    }

    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        xr: (f64, f64),
        yr: (f64, f64),
        caption: &str,
    ) -> Result<(), PlotError> {
        let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>("the mesh");
        let mut chart = panel_chart(area, xr, yr, caption).map_err(&err)?;
        chart.configure_mesh().disable_mesh().draw().map_err(&err)?;
        let inside = |p: &(f64, f64)| p.0 >= xr.0 && p.0 <= xr.1 && p.1 >= yr.0 && p.1 <= yr.1;
        let colours = [RGBColor(90, 90, 90), RGBColor(31, 90, 180)];
        for (edge, fine) in self.edges.iter().zip(&self.fine_edges) {
            if edge.iter().all(inside) {
                let style = ShapeStyle::from(&colours[usize::from(*fine)]).stroke_width(1);
                chart
                    .draw_series(LineSeries::new(edge.iter().copied(), style))
                    .map_err(&err)?;
            }
        }
        Ok(())
    }
}

impl Drawing for MeshDrawing {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let (left, right) = two_panels(root, &self.title)?;
        let r = self.extent;
        let h = r * aspect(&left);
        self.panel(
            &left,
            (-r, r),
            (-h, h),
            "whole gear (blue: fine teeth) [mm]",
        )?;
        let (xr, yr) = self.zoom;
        let half = 0.5 * (xr.1 - xr.0);
        let cy = 0.5 * (yr.0 + yr.1);
        let hh = half * aspect(&right);
        self.panel(&right, xr, (cy - hh, cy + hh), "fine teeth [mm]")
    }
}

/// Series colours of the charts, in order.
const PALETTE: [RGBColor; 9] = [
    RGBColor(31, 90, 180),
    RGBColor(200, 50, 40),
    RGBColor(20, 140, 60),
    RGBColor(150, 80, 170),
    RGBColor(230, 140, 20),
    RGBColor(60, 60, 60),
    RGBColor(0, 170, 190),
    RGBColor(170, 120, 60),
    RGBColor(230, 90, 160),
];

/// `text` with every path in it cut to its file name (a title or label must not carry the
/// folders of the machine it ran on): a space-separated word that starts with a separator or a
/// drive (`C:`), or holds two separators, keeps what follows its last one (a unit like `m/N`
/// stays).
pub fn without_folders(text: &str) -> String {
    let separator = |c: char| c == '/' || c == '\\';
    text.split(' ')
        .map(|word| {
            let drive = word.len() > 2 && word.as_bytes()[1] == b':';
            let path = word.starts_with(separator) || drive || word.matches(separator).count() >= 2;
            match path {
                true => word.rsplit(separator).next().unwrap_or(word),
                false => word,
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A line chart of one or more named series.
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<(String, Vec<(f64, f64)>)>,
    /// The y range drawn; `None`: the data's (one far series can then squash the others,
    /// e.g. a Harris map's unloaded-TE-dominated candidate).
    pub y_range: Option<(f64, f64)>,
    /// Named point sets drawn as markers (circles), e.g. measurements on a model's curve.
    pub markers: Vec<(String, Vec<(f64, f64)>)>,
}

impl Drawing for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>(&self.title);
        root.fill(&WHITE).map_err(&err)?;
        let points = self
            .series
            .iter()
            .chain(&self.markers)
            .flat_map(|(_, s)| s.iter())
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in points {
            x0 = x0.min(p.0);
            x1 = x1.max(p.0);
            y0 = y0.min(p.1);
            y1 = y1.max(p.1);
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        if let Some(range) = self.y_range {
            (y0, y1) = range;
        }
        let pad = 0.06 * (y1 - y0).max(1e-12 * y1.abs().max(1.0));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1.max(x0 + 1e-12), (y0 - pad)..(y1 + pad))
            .map_err(&err)?;
        let number = |v: &f64| {
            if *v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
                format!("{v:.3e}")
            } else {
                format!("{v:.3}")
            }
        };
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .y_label_formatter(&number)
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(&err)?;
        for (i, (name, data)) in self.series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            // A point that is not finite (a model that diverged there) breaks the line: no
            // segment is drawn across a gap the data do not cover.
            let runs = || data.split(|p| !p.1.is_finite());
            // A point alone between gaps has no line to be on: a dot.
            chart
                .draw_series(
                    runs()
                        .filter(|run| run.len() == 1)
                        .map(|run| Circle::new(run[0], 2, colour.filled())),
                )
                .map_err(&err)?;
            chart
                .draw_series(
                    runs()
                        .filter(|run| run.len() > 1)
                        .map(|run| PathElement::new(run.to_vec(), colour.stroke_width(2))),
                )
                .map_err(&err)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        for (i, (name, data)) in self.markers.iter().enumerate() {
            let colour = PALETTE[(self.series.len() + i) % PALETTE.len()];
            chart
                .draw_series(
                    data.iter()
                        .copied()
                        .filter(|p| p.1.is_finite())
                        .map(|p| Circle::new(p, 5, colour.filled())),
                )
                .map_err(&err)?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(&err)?;
        Ok(())
    }
}

/// A point (x, y) with its label.
pub type LabelledPoint = (f64, f64, String);

/// Labelled points on logarithmic axes, one marker shape and colour per series (an
/// accuracy-versus-cost chart). Points with a non-positive coordinate are left out.
pub struct LogScatter {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// (series name, points (x, y, label)).
    pub series: Vec<(String, Vec<LabelledPoint>)>,
    /// Per series, a level drawn as a dashed line in its colour (e.g. the uncertainty of the
    /// reference its errors are measured against: errors below it are not resolved).
    pub floors: Vec<Option<f64>>,
}

impl Drawing for LogScatter {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>(&self.title);
        root.fill(&WHITE).map_err(&err)?;
        let shown =
            |p: &&LabelledPoint| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
        let all: Vec<&LabelledPoint> = self
            .series
            .iter()
            .flat_map(|(_, s)| s.iter())
            .filter(shown)
            .collect();
        let range = |f: fn(&LabelledPoint) -> f64| {
            let lo = all.iter().map(|p| f(p)).fold(f64::INFINITY, f64::min);
            let hi = all.iter().map(|p| f(p)).fold(f64::NEG_INFINITY, f64::max);
            if lo.is_finite() {
                (lo / 3.0, hi * 3.0)
            } else {
                (1e-3, 1.0)
            }
        };
        let (x, mut y) = (range(|p| p.0), range(|p| p.1));
        // Room right of the rightmost marker for its label (about 20 characters, some 0.7 of a
        // decade at this width and span).
        let x = (x.0, x.1 * 4.0);
        for floor in self
            .floors
            .iter()
            .flatten()
            .filter(|f| **f > 0.0 && f.is_finite())
        {
            y = (y.0.min(floor / 3.0), y.1.max(floor * 3.0));
        }
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())
            .map_err(&err)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&|v| {
                if *v < 0.01 {
                    format!("{v:.0e}")
                } else {
                    format!("{v}")
                }
            })
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(&err)?;
        for (i, (name, points)) in self.series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            if let Some(floor) = self.floors.get(i).copied().flatten() {
                if floor > 0.0 && floor.is_finite() {
                    chart
                        .draw_series(DashedLineSeries::new(
                            [(x.0, floor), (x.1, floor)],
                            6,
                            4,
                            colour.stroke_width(1),
                        ))
                        .map_err(&err)?;
                }
            }
            let visible: Vec<&LabelledPoint> = points.iter().filter(shown).collect();
            chart
                .draw_series(
                    visible
                        .iter()
                        .map(|p| Circle::new((p.0, p.1), 5, colour.filled())),
                )
                .map_err(&err)?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
            chart
                .draw_series(visible.iter().map(|p| {
                    // Beside the marker, not on it (log axes: a factor).
                    Text::new(
                        p.2.clone(),
                        (p.0 * 1.15, p.1 * 1.04),
                        ("sans-serif", 11).into_font().color(&colour),
                    )
                }))
                .map_err(&err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(&err)?;
        Ok(())
    }
}

/// A colour map of scattered values (a waterfall of spectra: x = speed, y = frequency, colour =
/// amplitude on a log scale), each value drawn as a cell of the given size.
pub struct ColourMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// (x, y, value ≥ 0).
    pub cells: Vec<(f64, f64, f64)>,
    pub cell_size: (f64, f64),
    /// Decades of dynamic range shown below the largest value.
    pub decades: f64,
    /// What the colour shows, with its unit (the legend's label for the values of each decade).
    pub value_label: String,
    /// Curves drawn over the map (e.g. the natural frequencies in its coordinates).
    pub overlays: Vec<(String, Vec<(f64, f64)>)>,
}

impl Drawing for ColourMap {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        let err = plot_err::<DrawingAreaErrorKind<DB::ErrorType>>(&self.title);
        root.fill(&WHITE).map_err(&err)?;
        let fold = |f: fn(f64, f64) -> f64, init: f64, pick: fn(&(f64, f64, f64)) -> f64| {
            self.cells.iter().map(pick).fold(init, f)
        };
        let (x0, x1) = (
            fold(f64::min, f64::INFINITY, |c| c.0),
            fold(f64::max, f64::NEG_INFINITY, |c| c.0),
        );
        let (y0, y1) = (
            fold(f64::min, f64::INFINITY, |c| c.1) - 0.5 * self.cell_size.1,
            fold(f64::max, f64::NEG_INFINITY, |c| c.1) + 0.5 * self.cell_size.1,
        );
        let top = fold(f64::max, 0.0, |c| c.2).max(1e-300);
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1.max(x0 + 1e-9), y0..y1.max(y0 + 1e-9))
            .map_err(&err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(&err)?;
        let (w, h) = (0.5 * self.cell_size.0, 0.5 * self.cell_size.1);
        // 0 at `decades` below the top, 1 at the top; blue → green → yellow → red.
        let colour_of = |v: f64| {
            let t = (1.0 + (v / top).log10() / self.decades).clamp(0.0, 1.0);
            HSLColor(0.66 * (1.0 - t), 0.9, 0.25 + 0.35 * t)
        };
        chart
            .draw_series(self.cells.iter().filter(|c| c.2 > 0.0).map(|&(x, y, v)| {
                Rectangle::new([(x - w, y - h), (x + w, y + h)], colour_of(v).filled())
            }))
            .map_err(&err)?;
        // The legend: one swatch per decade below the top.
        for d in 0..=(self.decades.round() as i32) {
            let value = top * 10f64.powi(-d);
            let colour = colour_of(value);
            chart
                .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())
                .map_err(&err)?
                .label(format!("{value:.2e} {}", self.value_label))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 18, y + 6)], colour.filled())
                });
        }
        for (name, data) in &self.overlays {
            chart
                .draw_series(LineSeries::new(
                    data.iter().copied().filter(|p| p.1 >= y0 && p.1 <= y1),
                    BLACK.stroke_width(2),
                ))
                .map_err(&err)?
                .label(name.as_str())
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(&err)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::without_folders;

    #[test]
    fn titles_lose_the_folders_but_keep_units() {
        assert_eq!(
            without_folders(
                "/home/me/out/run/sweep-fe/stiffness.csv without 4.9e-10 m/N body twist"
            ),
            "stiffness.csv without 4.9e-10 m/N body twist"
        );
        assert_eq!(
            without_folders("run/sweep-fe/stiffness.csv"),
            "stiffness.csv"
        );
        assert_eq!(without_folders(r"C:\runs\k.csv"), "k.csv");
        assert_eq!(without_folders("ltca (relief none)"), "ltca (relief none)");
    }
}

#[cfg(test)]
mod line_gaps {
    use super::*;

    /// A series with a point that is not finite is drawn as two lines, none across the gap: the
    /// SVG holds one polyline per finite run (and the legend's sample line).
    #[test]
    fn a_gap_in_a_series_breaks_its_line() {
        let polylines = |data: Vec<(f64, f64)>| {
            let plot = LinePlot {
                title: "gap".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                series: vec![("s".into(), data)],
                y_range: None,
                markers: Vec::new(),
            };
            register_font();
            let mut text = String::new();
            {
                let area = SVGBackend::with_string(&mut text, (400, 300)).into_drawing_area();
                plot.draw(&area).unwrap();
                area.present().unwrap();
            }
            text.matches("<polyline").count()
        };
        let whole = polylines(vec![
            (0.0, 1.0),
            (1.0, 2.0),
            (2.0, 1.5),
            (3.0, 1.0),
            (4.0, 2.0),
        ]);
        let gap = polylines(vec![
            (0.0, 1.0),
            (1.0, 2.0),
            (2.0, f64::NAN),
            (3.0, 1.0),
            (4.0, 2.0),
        ]);
        assert_eq!(
            gap,
            whole + 1,
            "{whole} polylines without the gap, {gap} with it"
        );
    }
}
