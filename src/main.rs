//! The `geardyn` command line: each subcommand loads a case, calls the library and writes its
//! outputs through `geardyn::report`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use geardyn::case::{Case, EMBEDDED_DEFAULT};
use geardyn::fe::MassLumping;
use geardyn::report::{self, geometry::GeometrySummary, plot::PairDrawing};

/// Spur-gear mesh dynamics: exact geometry, loaded contact, explicit dynamics, lumped sweeps.
///
/// Every command takes an optional case file (TOML); without one it runs the embedded default
/// case, the seed paper's pair (Z1 = Z2 = 36, m = 3.18 mm, alpha = 20 deg, B = 25.4 mm).
/// Outputs go to a fresh folder under out/ unless --out is given.
#[derive(Parser)]
#[command(name = "geardyn", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The whole pipeline built so far on one case: geometry, meshes, LTCA (every relief
    /// variant) and the lumped speed sweep on the LTCA stiffness, each in its own sub-folder of
    /// one output folder.
    Run(CommonArgs),
    /// Derived geometry of the pair: radii, contact ratio, line of action, contact points,
    /// backlash, resolved reliefs; writes summary.json, a drawing (SVG, PNG) and profile CSVs.
    Geometry(CommonArgs),
    /// FE meshes of both gears (8-node quadrilaterals, fine on the teeth that engage at the mesh
    /// position): writes mesh_gear{1,2}.vtk (ParaView, meshio) and mesh_gear{1,2}.png, and
    /// prints element and node counts.
    Mesh {
        #[command(flatten)]
        common: CommonArgs,
        /// Relief variant of the case to mesh; default: the first one.
        #[arg(long, value_name = "NAME")]
        relief: Option<String>,
    },
    /// Quasi-static loaded tooth contact analysis over one base pitch for every relief variant
    /// (or the one named): static transmission error, load sharing and the mesh stiffness k(θ),
    /// next to ISO 6336-1 method B. Writes ltca_<variant>.csv, ste/stiffness/load-sharing plots
    /// (SVG, PNG) and summary.json.
    Ltca {
        #[command(flatten)]
        common: CommonArgs,
        /// Load torque on the driven gear [N·m]; default: the case's first operating point.
        #[arg(long, value_name = "T", allow_negative_numbers = true)]
        torque_nm: Option<f64>,
        /// Mesh positions over one base pitch.
        #[arg(long, default_value_t = 64, value_name = "N")]
        positions: usize,
        /// Only this relief variant; default: every variant of the case.
        #[arg(long, value_name = "NAME")]
        relief: Option<String>,
    },
    /// Speed sweep of the 1-DOF lumped mesh model driven by the mesh stiffness k(θ): periodic
    /// steady state per driver speed (up- and down-sweep), DTE rms and peak-to-peak, dynamic
    /// factor, separation, mesh-harmonic amplitudes, Floquet stability. Writes sweep.csv, plots
    /// and summary.json.
    Sweep {
        #[command(flatten)]
        common: CommonArgs,
        /// Driver speeds FROM:TO:N in rpm.
        #[arg(long, default_value = "100:12000:600", value_name = "FROM:TO:N")]
        rpm: String,
        #[command(flatten)]
        model: LumpedArgs,
        /// Also run up through the same speed range in this many seconds (a linear speed ramp,
        /// transient): writes runup.csv and runup.png.
        #[arg(long, value_name = "SECONDS")]
        run_up_s: Option<f64>,
    },
    /// Floquet stability map of the linear time-periodic mesh model over a speed range:
    /// the largest multiplier of the monodromy matrix per driver speed (> 1: parametric
    /// instability, near f_mesh ≈ 2 f_n / j). Writes stability.csv, a plot and summary.json.
    Stability {
        #[command(flatten)]
        common: CommonArgs,
        /// Driver speeds FROM:TO:N in rpm.
        #[arg(long, default_value = "100:20000:2000", value_name = "FROM:TO:N")]
        rpm: String,
        #[command(flatten)]
        model: LumpedArgs,
    },
    /// Explicit dynamic contact FE of the meshing pair (central difference, penalty contact with
    /// Coulomb friction, corotational bodies on rigid hubs): a scene of the case, or a speed and
    /// a duration. Writes history.csv (DTE, speeds, contact forces, db5 impacts, energy),
    /// dte_spectrum.csv, stiffness.csv (k from the DTE, readable by sweep --stiffness), plots
    /// and summary.json; a diverged run keeps what it computed and says why.
    Fe {
        #[command(flatten)]
        common: CommonArgs,
        #[command(flatten)]
        options: FeArgs,
    },
    /// Validation studies too wide for the test suite; each writes a table (CSV and Markdown) and
    /// summary.json. Studies: integrators — where each fixed-step scheme of the lumped model
    /// fails (stability and 1 % frequency-accuracy limits in ωh, predicted vs observed; order of
    /// convergence with and without tooth separation) on the case's effective mass and mean
    /// mesh stiffness.
    Validate {
        /// The study: integrators.
        #[arg(value_name = "STUDY")]
        study: String,
        #[command(flatten)]
        common: CommonArgs,
        #[command(flatten)]
        model: LumpedArgs,
    },
    /// Prints a case file: the given one, or the embedded default (start your own from it:
    /// `geardyn case > my.toml`).
    Case {
        /// Case file to check and print; default: the embedded paper36 case.
        case: Option<PathBuf>,
    },
}

/// The lumped model's options, shared by `sweep` and `stability`; each overrides the case's
/// `[lumped]` section.
#[derive(Args, Clone, Default)]
struct LumpedArgs {
    /// Stiffness source: ltca (the case's FE, first relief variant), pe (potential energy),
    /// iso (ISO 6336-1 c_gamma_alpha, constant) or a CSV file with columns roll_angle_deg,
    /// mesh_stiffness_n_per_m[, unloaded_te_um] over one mesh period. Default: the case's
    /// lumped.stiffness (ltca).
    #[arg(long, value_name = "SOURCE")]
    stiffness: Option<String>,
    /// Mesh damping ratio ζ (c = 2ζ√(k̄ m)); default: the case's lumped.damping_ratio.
    #[arg(long, value_name = "ZETA")]
    damping_ratio: Option<f64>,
    /// Load torque on the driven gear [N·m]; default: the case's first operating point.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    torque_nm: Option<f64>,
    /// How the pair is driven. torque: both gears free, input and load torques (the torsional
    /// 2-DOF reduces exactly to the relative coordinate with m_e = I₁I₂/(I₁r_b2² + I₂r_b1²));
    /// speed: the driver turns at the prescribed speed, as in the explicit FE (m = I₂/r_b2²).
    /// Default: the case's lumped.drive.
    #[arg(long, value_name = "DRIVE")]
    drive: Option<String>,
    /// Add each gear's translation on its bearings along the line of action (3 DOFs; stiffness,
    /// damping and masses from the case's [lumped] section).
    #[arg(long)]
    bearings: bool,
}

/// Options of `geardyn fe`.
#[derive(Args, Clone, Default)]
struct FeArgs {
    /// A scene of the case ([[scene]]), e.g. low-unmodified; the options below override it.
    #[arg(long, value_name = "NAME")]
    scene: Option<String>,
    /// Driver speed [rpm] (without --scene: required).
    #[arg(long, value_name = "RPM")]
    speed_rpm: Option<f64>,
    /// Simulated time [s] (without --scene: required); shortens or lengthens a scene.
    #[arg(long, value_name = "SECONDS")]
    duration_s: Option<f64>,
    /// Load torque on the driven gear [N·m]; default: the scene's, or the first operating point.
    #[arg(long, value_name = "T")]
    torque_nm: Option<f64>,
    /// Relief variant; default: the scene's, or the first variant.
    #[arg(long, value_name = "NAME")]
    relief: Option<String>,
    /// Coulomb friction coefficient; default: the scene's, or 0.
    #[arg(long, value_name = "MU")]
    friction: Option<f64>,
    /// Ramp time of speed and torque [s]; default: the scene's, or min(0.01, duration/10).
    #[arg(long, value_name = "SECONDS")]
    ramp_s: Option<f64>,
    /// Time step over the critical step (fe.step_factor, default 0.9); above 1 the run diverges.
    #[arg(long, value_name = "BETA")]
    step_factor: Option<f64>,
    /// Contact penalty over the master element's largest diagonal stiffness (fe.penalty_factor).
    #[arg(long, value_name = "F")]
    penalty_factor: Option<f64>,
    /// Lumped mass of the bodies: corner-twelfth (longer step) or hrz (fe.mass_lumping).
    #[arg(long, value_name = "SCHEME", value_parser = parse_mass_lumping)]
    mass_lumping: Option<MassLumping>,
    /// Damping ratio of the mesh mode, a dashpot on the DTE rate (fe.mesh_damping_ratio).
    #[arg(long, value_name = "ZETA")]
    mesh_damping_ratio: Option<f64>,
    /// Flank element size of the explicit mesh [mm] (fe.explicit_fine_element_mm).
    #[arg(long, value_name = "MM")]
    fine_element_mm: Option<f64>,
    /// Largest element size of the explicit mesh: other teeth, body [mm]
    /// (fe.explicit_coarse_element_mm).
    #[arg(long, value_name = "MM")]
    coarse_element_mm: Option<f64>,
}

#[derive(Args)]
struct CommonArgs {
    /// Case file (TOML). Default: the embedded paper36 case.
    case: Option<PathBuf>,
    /// Output folder. Default: a fresh folder out/<command>-<case>-NNN.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(&args),
        Command::Geometry(args) => geometry(&args),
        Command::Mesh { common, relief } => mesh(&common, relief.as_deref()),
        Command::Ltca {
            common,
            torque_nm,
            positions,
            relief,
        } => ltca(&common, torque_nm, positions, relief.as_deref()),
        Command::Sweep {
            common,
            rpm,
            model,
            run_up_s,
        } => sweep(&common, &rpm, &model, run_up_s),
        Command::Stability { common, rpm, model } => stability(&common, &rpm, &model),
        Command::Fe { common, options } => fe(&common, &options),
        Command::Validate {
            study,
            common,
            model,
        } => validate(&study, &common, &model),
        Command::Case { case } => print_case(case.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn load_case(path: Option<&Path>) -> Result<Case> {
    Ok(match path {
        Some(p) => Case::load(p)?,
        None => Case::embedded_default()?,
    })
}

/// The output folder: the one asked for (created), or a fresh one under out/.
fn output_dir(out: Option<&Path>, command: &str, case: &Case) -> Result<PathBuf> {
    match out {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create output folder {}", dir.display()))?;
            Ok(dir.to_path_buf())
        }
        None => report::fresh_output_dir(Path::new("out"), command, case.name())
            .context("cannot create an output folder under out/"),
    }
}

fn run(args: &CommonArgs) -> Result<()> {
    let case = load_case(args.case.as_deref())?;
    let dir = output_dir(args.out.as_deref(), "run", &case)?;
    let stage = |name: &str| CommonArgs {
        case: args.case.clone(),
        out: Some(dir.join(name)),
    };
    println!("== geometry");
    geometry(&stage("geometry"))?;
    println!("\n== mesh");
    mesh(&stage("mesh"), None)?;
    println!("\n== ltca");
    ltca(&stage("ltca"), None, 64, None)?;
    println!("\n== sweep");
    sweep(
        &stage("sweep"),
        "100:12000:600",
        &LumpedArgs::default(),
        None,
    )?;
    println!("\nall outputs in {}", dir.display());
    Ok(())
}

fn geometry(args: &CommonArgs) -> Result<()> {
    let case = load_case(args.case.as_deref())?;
    let dir = output_dir(args.out.as_deref(), "geometry", &case)?;
    let summary = GeometrySummary::new(&case);
    print!("{}", summary.table());

    let write = |name: &str, bytes: &[u8]| {
        report::write_atomic(&dir.join(name), bytes)
            .with_context(|| format!("cannot write {}", dir.join(name).display()))
    };
    write("case.toml", case.text.as_bytes())?;
    write("geometry.txt", summary.table().as_bytes())?;
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;

    let c = case.pair.contact_points;
    let rows = c.named().into_iter().map(|(name, s)| {
        let p = case.pair.loa_point(s);
        vec![
            name.to_string(),
            format!("{:.9}", s * 1e3),
            format!("{:.9}", case.pair.roll_angle_at(1, s).to_degrees()),
            format!("{:.9}", case.pair.roll_angle_at(2, s).to_degrees()),
            format!("{:.9}", p.x * 1e3),
            format!("{:.9}", p.y * 1e3),
        ]
    });
    let header = [
        "point",
        "distance_from_t1_mm",
        "roll_angle_gear1_deg",
        "roll_angle_gear2_deg",
        "x_mm",
        "y_mm",
    ];
    report::write_csv(&dir.join("contact_points.csv"), &header, rows)
        .context("cannot write contact_points.csv")?;

    for variant in &case.relief_variants {
        for gear in 1..=2 {
            let name = format!("profile_{}_gear{gear}.csv", variant.name);
            let rows =
                report::geometry::profile_rows(&case, gear, &variant.modifications[gear - 1]);
            report::write_csv(&dir.join(&name), &report::geometry::PROFILE_HEADER, rows)
                .with_context(|| format!("cannot write {name}"))?;
        }
    }

    // The drawing shows the first variant with relief, if any (relief is µm-scale: the CSVs carry it).
    let variant = case
        .relief_variants
        .iter()
        .find(|v| !v.modifications.iter().all(|m| m.is_none()))
        .or(case.relief_variants.first());
    let modifications = variant.map(|v| v.modifications).unwrap_or_default();
    let title = format!(
        "{}: z = {}/{}, m = {} mm, contact ratio {:.4}{}",
        case.name(),
        case.pair.gears[0].teeth(),
        case.pair.gears[1].teeth(),
        case.file.tool.module_mm,
        case.pair.contact_ratio,
        variant
            .map(|v| format!(", relief \"{}\"", v.name))
            .unwrap_or_default()
    );
    let drawing = PairDrawing::new(&case.pair, &modifications, title);
    report::plot::draw_svg_and_png(
        &dir.join("pair.svg"),
        &dir.join("pair.png"),
        (1800, 900),
        &drawing,
    )?;
    println!("\nwrote {}", dir.display());
    Ok(())
}

fn mesh(args: &CommonArgs, relief: Option<&str>) -> Result<()> {
    use geardyn::geometry::Side;
    let case = load_case(args.case.as_deref())?;
    let variant = match relief {
        Some(name) => case.relief_variant(name).with_context(|| {
            let names: Vec<&str> = case
                .relief_variants
                .iter()
                .map(|v| v.name.as_str())
                .collect();
            format!("no relief variant {name:?} in the case; it has {names:?}")
        })?,
        None => case
            .relief_variants
            .first()
            .context("the case has no relief variant")?,
    };
    let dir = output_dir(args.out.as_deref(), "mesh", &case)?;
    report::write_atomic(&dir.join("case.toml"), case.text.as_bytes())
        .context("cannot write case.toml")?;
    for index in 1..=2 {
        let gear = case.pair.gear(index);
        let z = gear.teeth() as usize;
        // The teeth around the mesh position: the tooth at the pitch point and its neighbours.
        let fine_teeth = vec![z - 1, 0, 1];
        let started = std::time::Instant::now();
        let mesh = geardyn::mesh::mesh_gear(
            gear,
            &variant.modifications[index - 1],
            &case.mesh_spec(fine_teeth),
        );
        let wall = started.elapsed().as_secs_f64();
        geardyn::fe::assembly::check_elements(&mesh.nodes, &mesh.elements)?;
        println!(
            "gear{index}: {} elements ({} on fine teeth), {} nodes, {} bore nodes, {} nodes on a fine flank; meshed in {:.3} s",
            mesh.elements.len(),
            mesh.element_fine.iter().filter(|f| **f).count(),
            mesh.nodes.len(),
            mesh.bore_nodes.len(),
            mesh.flank(0, Side::Left).nodes.len(),
            wall
        );
        let title = format!("{} gear{index}, relief \"{}\"", case.name(), variant.name);
        let vtk = report::vtk::mesh_to_vtk(&title, &mesh.nodes, &mesh.elements, &mesh.element_fine);
        report::write_atomic(&dir.join(format!("mesh_gear{index}.vtk")), vtk.as_bytes())
            .context("cannot write the VTK file")?;
        let centre = nalgebra::Point2::new(0.0, gear.reference_radius);
        let drawing = report::plot::MeshDrawing::new(
            &mesh,
            centre,
            2.2 * gear.module() * std::f64::consts::PI / 2.0 + gear.module(),
            title,
        );
        report::plot::draw_png(
            &dir.join(format!("mesh_gear{index}.png")),
            (1800, 900),
            &drawing,
        )?;
    }
    println!("wrote {}", dir.display());
    Ok(())
}

fn ltca(
    args: &CommonArgs,
    torque_nm: Option<f64>,
    positions: usize,
    relief: Option<&str>,
) -> Result<()> {
    use geardyn::report::ltca as rep;
    use indicatif::{ProgressBar, ProgressStyle};

    let started = std::time::Instant::now();
    let case = load_case(args.case.as_deref())?;
    let torque = load_torque(&case, torque_nm)?;
    let variants: Vec<_> = match relief {
        Some(name) => vec![case
            .relief_variant(name)
            .with_context(|| format!("no relief variant {name:?} in the case"))?],
        None => case.relief_variants.iter().collect(),
    };
    let dir = output_dir(args.out.as_deref(), "ltca", &case)?;
    report::write_atomic(&dir.join("case.toml"), case.text.as_bytes())
        .context("cannot write case.toml")?;
    let rb2 = case.pair.gears[1].base_radius;
    let mut summaries = Vec::new();
    let mut ste_series = Vec::new();
    let mut k_series = Vec::new();
    for variant in &variants {
        eprintln!(
            "relief variant \"{}\": meshing and factorizing both gears ...",
            variant.name
        );
        let model = ltca_model(&case, &variant.modifications)?;
        let bar = ProgressBar::new(positions as u64);
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} positions, ETA {eta}")
                .expect("valid template"),
        );
        bar.set_message(format!("LTCA \"{}\"", variant.name));
        let cycle_started = std::time::Instant::now();
        let results = model.run(positions, torque, &|done| bar.set_position(done as u64))?;
        let cycle_s = cycle_started.elapsed().as_secs_f64();
        bar.finish_and_clear();
        let [b1, b2] = &model.bodies;
        let summary = rep::variant_summary(
            &variant.name,
            &results,
            rb2,
            [b1.mesh.elements.len(), b2.mesh.elements.len()],
            [b1.free_dofs, b2.free_dofs],
            (
                b1.factorization_s + b2.factorization_s,
                b1.condensation_s + b2.condensation_s,
                cycle_s,
            ),
        );
        let name = format!("ltca_{}.csv", variant.name);
        report::write_csv(
            &dir.join(&name),
            &rep::position_header(&model.tooth_pairs)
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
            rep::position_rows(&results, rb2),
        )
        .with_context(|| format!("cannot write {name}"))?;
        let deg = |r: &geardyn::ltca::PositionResult| r.roll_angle.to_degrees();
        ste_series.push((
            format!("{} loaded", variant.name),
            results
                .iter()
                .map(|r| (deg(r), r.ste * rb2 * 1e6))
                .collect(),
        ));
        if !variant.modifications.iter().all(|m| m.is_none()) {
            ste_series.push((
                format!("{} unloaded", variant.name),
                results
                    .iter()
                    .map(|r| (deg(r), r.unloaded_te * rb2 * 1e6))
                    .collect(),
            ));
        }
        k_series.push((
            variant.name.clone(),
            results.iter().map(|r| (deg(r), r.mesh_stiffness)).collect(),
        ));
        let sharing = report::plot::LinePlot {
            title: format!(
                "{}: load per tooth pair, relief \"{}\", T = {torque} N·m",
                case.name(),
                variant.name
            ),
            x_label: "driver roll angle [deg]".into(),
            y_label: "normal force [N]".into(),
            series: model
                .tooth_pairs
                .iter()
                .enumerate()
                .map(|(i, (t1, t2))| {
                    (
                        format!("pair {t1}/{t2}"),
                        results.iter().map(|r| (deg(r), r.pair_forces[i])).collect(),
                    )
                })
                .collect(),
        };
        let stem = format!("load_sharing_{}", variant.name);
        report::plot::save_chart(&dir, &stem, &sharing)?;
        println!(
            "{:<16} k mean {:.4e} min {:.4e} max {:.4e} N/m, STE mean {:.3} um p-p {:.3} um, KKT <= {:.1e}",
            variant.name,
            summary.mesh_stiffness_mean_n_per_m,
            summary.mesh_stiffness_min_n_per_m,
            summary.mesh_stiffness_max_n_per_m,
            summary.ste_mean_um,
            summary.ste_peak_to_peak_um,
            summary.max_kkt_residual
        );
        summaries.push(summary);
    }
    let ste_plot = report::plot::LinePlot {
        title: format!(
            "{}: static transmission error, T = {torque} N·m",
            case.name()
        ),
        x_label: "driver roll angle [deg]".into(),
        y_label: "transmission error along the LOA [um]".into(),
        series: ste_series,
    };
    report::plot::save_chart(&dir, "ste", &ste_plot)?;
    let pe = geardyn::stiffness::potential_energy::potential_energy_table(
        &case.pair,
        positions,
        case.material.youngs_modulus,
        case.material.poisson_ratio,
        case.file.fe.plane,
    );
    let iso =
        geardyn::stiffness::iso_6336_method_b(&case.pair, torque, case.material.youngs_modulus);
    let pe_curve: Vec<(f64, f64)> = pe
        .roll_angles
        .iter()
        .zip(&pe.stiffness)
        .map(|(x, k)| (x.to_degrees(), *k))
        .collect();
    k_series.push(("potential energy (unmodified)".into(), pe_curve.clone()));
    let (x0, x1) = (
        pe.roll_angles[0].to_degrees(),
        pe.roll_angles[positions - 1].to_degrees(),
    );
    k_series.push((
        "ISO 6336-1 c_gamma_alpha * b".into(),
        vec![(x0, iso.mean_n_per_m), (x1, iso.mean_n_per_m)],
    ));
    report::write_csv(
        &dir.join("stiffness_potential_energy.csv"),
        &["roll_angle_deg", "mesh_stiffness_n_per_m"],
        pe_curve
            .iter()
            .map(|(x, k)| vec![format!("{x:.6}"), format!("{k:.6e}")]),
    )
    .context("cannot write stiffness_potential_energy.csv")?;
    let k_plot = report::plot::LinePlot {
        title: format!("{}: mesh stiffness, T = {torque} N·m", case.name()),
        x_label: "driver roll angle [deg]".into(),
        y_label: "mesh stiffness [N/m]".into(),
        series: k_series,
    };
    report::plot::save_chart(&dir, "stiffness", &k_plot)?;

    println!(
        "potential energy: mean {:.4e} N/m (min {:.4e}, max {:.4e})",
        pe.mean(),
        pe.min(),
        pe.max()
    );
    println!(
        "ISO 6336-1 method B: c_gamma_alpha*b = {:.4e} N/m, c'*b = {:.4e} N/m",
        iso.mean_n_per_m, iso.single_pair_n_per_m
    );
    let first = &summaries[0];
    let summary = serde_json::json!({
        "case": case.name(),
        "torque_nm": torque,
        "positions": positions,
        "plane": case.file.fe.plane,
        "fine_element_mm": case.file.mesh.fine_element_mm,
        "coarse_element_mm": case.file.mesh.coarse_element_mm,
        "relief_variant": first.relief_variant,
        "mesh_stiffness_mean_n_per_m": first.mesh_stiffness_mean_n_per_m,
        "mesh_stiffness_min_n_per_m": first.mesh_stiffness_min_n_per_m,
        "mesh_stiffness_max_n_per_m": first.mesh_stiffness_max_n_per_m,
        "ste_mean_um": first.ste_mean_um,
        "ste_peak_to_peak_um": first.ste_peak_to_peak_um,
        "iso_c_gamma_n_per_m": iso.mean_n_per_m,
        "iso_c_prime_n_per_m": iso.single_pair_n_per_m,
        "potential_energy_mean_n_per_m": pe.mean(),
        "potential_energy_min_n_per_m": pe.min(),
        "potential_energy_max_n_per_m": pe.max(),
        "elements": first.elements[0] + first.elements[1],
        "wall_s": started.elapsed().as_secs_f64(),
        "variants": summaries,
        "model": "2D FE (Q8), bores held rigid; frictionless node-to-surface contact on the drive flanks; one base pitch",
    });
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;
    println!("wrote {}", dir.display());
    Ok(())
}

/// Both gear bodies of the case, meshed fine on the engaging teeth, factorized and condensed.
fn ltca_model(
    case: &Case,
    modifications: &[geardyn::geometry::FlankModification; 2],
) -> Result<geardyn::ltca::LtcaModel> {
    use geardyn::ltca::{body::BodyMaterial, engaging_teeth, LtcaModel};
    let teeth = engaging_teeth(&case.pair);
    let material = BodyMaterial {
        youngs_modulus: case.material.youngs_modulus,
        poisson_ratio: case.material.poisson_ratio,
        plane: case.file.fe.plane,
    };
    let specs = [
        case.mesh_spec(teeth[0].clone()),
        case.mesh_spec(teeth[1].clone()),
    ];
    Ok(LtcaModel::new(&case.pair, modifications, specs, material)?)
}

/// The load torque on the driven gear: the one asked for, or the case's first operating point.
fn load_torque(case: &Case, torque_nm: Option<f64>) -> Result<f64> {
    let torque = match torque_nm {
        Some(t) => t,
        None => case
            .operating_points
            .first()
            .map(|o| o.torque)
            .context("the case has no operating point: give --torque-nm")?,
    };
    if !(torque > 0.0 && torque.is_finite()) {
        anyhow::bail!(
            "--torque-nm {torque} is invalid: the model needs a load torque > 0 on the driven gear"
        );
    }
    Ok(torque)
}

/// The case file's names (`fe.mass_lumping`), so the two spellings cannot drift apart.
fn parse_mass_lumping(text: &str) -> std::result::Result<MassLumping, String> {
    use serde::de::{value::Error, Deserialize, IntoDeserializer};
    MassLumping::deserialize(IntoDeserializer::<Error>::into_deserializer(text))
        .map_err(|_| format!("unknown mass lumping '{text}': give corner-twelfth or hrz"))
}

fn parse_range(text: &str) -> Result<Vec<f64>> {
    let parts: Vec<&str> = text.split(':').collect();
    let bad = || {
        anyhow::anyhow!("--rpm {text:?} is invalid: write FROM:TO:N with 0 < FROM < TO and N ≥ 2, e.g. 100:12000:600")
    };
    if parts.len() != 3 {
        return Err(bad());
    }
    let (from, to): (f64, f64) = (
        parts[0].parse().map_err(|_| bad())?,
        parts[1].parse().map_err(|_| bad())?,
    );
    let n: usize = parts[2].parse().map_err(|_| bad())?;
    if !(from > 0.0 && to > from && n >= 2) {
        return Err(bad());
    }
    Ok((0..n)
        .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
        .collect())
}

/// Everything the lumped commands share: the case, the speeds, and the model on the chosen
/// stiffness source.
struct LumpedSetup {
    case: Case,
    rpms: Vec<f64>,
    torque: f64,
    model: geardyn::lumped::MeshModel,
    source_name: String,
    stiffness_wall_s: f64,
    inertias: (f64, f64),
    effective_mass: f64,
    fn_hz: f64,
    drive: String,
    damping_ratio: f64,
    /// One line saying which model was used and what it leaves out.
    model_note: String,
}

/// A stiffness source named in a case file is relative to the case file's folder.
fn stiffness_path(case: &Case, from_case_file: bool, name: &str) -> PathBuf {
    let path = PathBuf::from(name);
    if from_case_file && path.is_relative() && case.source != geardyn::case::EMBEDDED_SOURCE {
        if let Some(dir) = Path::new(&case.source).parent() {
            return dir.join(path);
        }
    }
    path
}

fn lumped_setup(args: &CommonArgs, rpm: &str, options: &LumpedArgs) -> Result<LumpedSetup> {
    use geardyn::lumped::{Bearings, MeshModel, PeriodicTable};
    let case = load_case(args.case.as_deref())?;
    let settings = case.file.lumped.clone();
    let source = options
        .stiffness
        .clone()
        .unwrap_or(settings.stiffness.clone());
    let damping_ratio = options.damping_ratio.unwrap_or(settings.damping_ratio);
    let drive = options.drive.clone().unwrap_or(settings.drive.clone());
    let with_bearings = options.bearings || settings.bearings;
    let rpms = parse_range(rpm)?;
    if !(0.0..1.0).contains(&damping_ratio) {
        anyhow::bail!(
            "--damping-ratio {damping_ratio} is invalid: use a value in [0, 1), typically 0.02–0.1"
        );
    }
    let torque = load_torque(&case, options.torque_nm)?;
    let pair = &case.pair;
    let period = pair.gears[0].angular_pitch();
    let positions = 64;
    let stiffness_started = std::time::Instant::now();
    let (stiffness, unloaded_te, source_name) = match source.as_str() {
        "ltca" => {
            let variant = case
                .relief_variants
                .first()
                .context("the case has no relief variant")?;
            eprintln!(
                "computing the LTCA stiffness (relief \"{}\") ...",
                variant.name
            );
            let model = ltca_model(&case, &variant.modifications)?;
            let results = model.run(positions, torque, &|_| {})?;
            let rb2 = pair.gears[1].base_radius;
            (
                PeriodicTable {
                    period,
                    values: results.iter().map(|r| r.mesh_stiffness).collect(),
                },
                PeriodicTable {
                    period,
                    values: results.iter().map(|r| r.unloaded_te * rb2).collect(),
                },
                format!("ltca (relief {})", variant.name),
            )
        }
        "pe" => {
            let table = geardyn::stiffness::potential_energy::potential_energy_table(
                pair,
                positions,
                case.material.youngs_modulus,
                case.material.poisson_ratio,
                case.file.fe.plane,
            );
            (
                PeriodicTable {
                    period,
                    values: table.stiffness,
                },
                PeriodicTable::constant(period, 0.0),
                "potential-energy".to_string(),
            )
        }
        "iso" => {
            let iso =
                geardyn::stiffness::iso_6336_method_b(pair, torque, case.material.youngs_modulus);
            let table = iso.table(pair, positions);
            (
                PeriodicTable {
                    period,
                    values: table.stiffness,
                },
                PeriodicTable::constant(period, 0.0),
                "iso6336 (constant c_gamma_alpha)".to_string(),
            )
        }
        file if file.ends_with(".csv") => {
            let path = stiffness_path(&case, options.stiffness.is_none(), file);
            let (k, te) = report::stiffness_csv::read_stiffness_csv(&path, period)
                .map_err(anyhow::Error::msg)?;
            (k, te, format!("csv ({})", path.display()))
        }
        other => anyhow::bail!(
            "stiffness source {other:?} is unknown: use ltca, pe, iso or a .csv file with columns roll_angle_deg, mesh_stiffness_n_per_m[, unloaded_te_um]"
        ),
    };
    let stiffness_wall_s = stiffness_started.elapsed().as_secs_f64();
    let (i1, i2) = match settings.inertia_kg_mm2 {
        Some([a, b]) => (a * 1e-6, b * 1e-6),
        None => {
            let inertia = |i: usize| {
                let gear = &pair.gears[i];
                case.material.density * gear.spec.face_width * gear.area_moments().1
            };
            (inertia(0), inertia(1))
        }
    };
    let (rb1, rb2) = (pair.gears[0].base_radius, pair.gears[1].base_radius);
    let effective_mass = match drive.as_str() {
        "torque" => i1 * i2 / (i1 * rb2 * rb2 + i2 * rb1 * rb1),
        "speed" => i2 / (rb2 * rb2),
        other => anyhow::bail!("--drive {other:?} is unknown: use torque or speed"),
    };
    let backlash = (pair.backlash_normal > 1e-9).then_some(pair.backlash_normal);
    let bearings = with_bearings.then(|| {
        let mass = settings.gear_mass_kg.unwrap_or_else(|| {
            std::array::from_fn(|i| {
                let gear = &pair.gears[i];
                case.material.density * gear.spec.face_width * gear.area_moments().0
            })
        });
        let stiffness = settings.bearing_stiffness_n_per_m;
        Bearings {
            mass,
            stiffness,
            damping: std::array::from_fn(|i| {
                2.0 * settings.bearing_damping_ratio * (stiffness[i] * mass[i]).sqrt()
            }),
        }
    });
    let mut model = MeshModel {
        effective_mass,
        stiffness,
        unloaded_te,
        damping: 0.0,
        force: torque / rb2,
        backlash,
        bearings,
    };
    // A coefficient in the case wins over the case's ratio; --damping-ratio wins over both.
    let damping_ratio = match (options.damping_ratio, settings.mesh_damping_n_s_per_m) {
        (None, Some(c)) => c / model.damping_from_ratio(1.0),
        _ => damping_ratio,
    };
    model.damping = model.damping_from_ratio(damping_ratio);
    let fn_hz = model.natural_frequency() / (2.0 * std::f64::consts::PI);
    let model_note = match &model.bearings {
        None => format!(
            "1-DOF along the line of action ({drive} drive; the torsional 2-DOF with rigid shafts and bearings reduced exactly: torque drive -> relative coordinate, speed drive -> driven gear only); mesh stiffness periodic in the driver roll angle"
        ),
        Some(b) => format!(
            "3-DOF: relative rotation along the line of action ({drive} drive) + each gear's translation on its bearings along the line of action (k_b = {:.3e} / {:.3e} N/m, m = {:.3} / {:.3} kg); translations across the line of action left out (a frictionless spur mesh force does not excite them)",
            b.stiffness[0], b.stiffness[1], b.mass[0], b.mass[1]
        ),
    };
    println!(
        "stiffness {source_name}: mean {:.4e} N/m; I1 = {:.1} kg·mm², I2 = {:.1} kg·mm², m_e = {:.4} kg; f_n = {:.1} Hz; {}",
        model.stiffness.mean(),
        i1 * 1e6,
        i2 * 1e6,
        effective_mass,
        fn_hz,
        match backlash {
            Some(j) => format!("backlash {:.2} um (separation modelled)", j * 1e6),
            None => "zero backlash (no separation: the back flank engages at once)".into(),
        }
    );
    println!("model: {model_note}");

    Ok(LumpedSetup {
        case,
        rpms,
        torque,
        model,
        source_name,
        stiffness_wall_s,
        inertias: (i1, i2),
        effective_mass,
        fn_hz,
        drive,
        damping_ratio,
        model_note,
    })
}

fn sweep(args: &CommonArgs, rpm: &str, options: &LumpedArgs, run_up_s: Option<f64>) -> Result<()> {
    use geardyn::sweep as sw;
    let started = std::time::Instant::now();
    let LumpedSetup {
        case,
        rpms,
        torque,
        model,
        source_name,
        stiffness_wall_s,
        inertias: (i1, i2),
        effective_mass,
        fn_hz,
        drive,
        damping_ratio,
        model_note,
    } = lumped_setup(args, rpm, options)?;
    let pair = &case.pair;
    let dir = output_dir(args.out.as_deref(), "sweep", &case)?;
    report::write_atomic(&dir.join("case.toml"), case.text.as_bytes())
        .context("cannot write case.toml")?;
    // The stiffness the sweep used, in the file format every source reads back.
    let samples = model
        .stiffness
        .values
        .len()
        .max(model.unloaded_te.values.len());
    let roll_angles: Vec<f64> = (0..samples)
        .map(|j| j as f64 * model.stiffness.period / samples as f64)
        .collect();
    report::stiffness_csv::write_stiffness_csv(
        &dir.join("stiffness.csv"),
        &roll_angles,
        &roll_angles
            .iter()
            .map(|t| model.stiffness.at(*t))
            .collect::<Vec<_>>(),
        &roll_angles
            .iter()
            .map(|t| model.unloaded_te.at(*t))
            .collect::<Vec<_>>(),
    )
    .context("cannot write stiffness.csv")?;
    let sweep_started = std::time::Instant::now();
    let (up, down) = sw::sweep(&model, &rpms);
    let wall_s = sweep_started.elapsed().as_secs_f64();

    let header = [
        "driver_rpm",
        "mesh_hz",
        "dte_rms_up_um",
        "dte_rms_down_um",
        "dte_pp_up_um",
        "dynamic_factor_up",
        "dynamic_factor_down",
        "separated_up",
        "h1_um",
        "h2_um",
        "h3_um",
        "h4_um",
        "h5_um",
        "floquet_max_multiplier",
        "periods_up",
        "converged_up",
        "peak1_hz",
        "peak1_um",
        "peak2_hz",
        "peak2_um",
        "peak3_hz",
        "peak3_um",
    ];
    let rows = up.iter().zip(&down).map(|(u, d)| {
        let mut row = vec![
            format!("{:.3}", u.driver_speed_rpm),
            format!("{:.3}", u.mesh_frequency_hz),
            format!("{:.6}", u.dte_rms * 1e6),
            format!("{:.6}", d.dte_rms * 1e6),
            format!("{:.6}", u.dte_peak_to_peak * 1e6),
            format!("{:.6}", u.dynamic_factor),
            format!("{:.6}", d.dynamic_factor),
            u.separated.to_string(),
        ];
        row.extend(u.harmonics.iter().map(|h| format!("{:.6}", h * 1e6)));
        row.extend([
            format!("{:.6}", u.floquet),
            u.periods.to_string(),
            u.converged.to_string(),
        ]);
        for k in 0..geardyn::sweep::PEAKS {
            match u.peaks.get(k) {
                Some((hz, a)) => row.extend([format!("{hz:.3}"), format!("{:.6}", a * 1e6)]),
                None => row.extend([String::new(), String::new()]),
            }
        }
        row
    });
    report::write_csv(&dir.join("sweep.csv"), &header, rows).context("cannot write sweep.csv")?;

    let curve =
        |points: &[geardyn::sweep::SweepPoint],
         f: &dyn Fn(&geardyn::sweep::SweepPoint) -> f64|
         -> Vec<(f64, f64)> { points.iter().map(|p| (p.driver_speed_rpm, f(p))).collect() };
    let plots = [
        (
            "response",
            "DTE rms along the LOA [um]",
            vec![
                ("up-sweep".to_string(), curve(&up, &|p| p.dte_rms * 1e6)),
                ("down-sweep".to_string(), curve(&down, &|p| p.dte_rms * 1e6)),
            ],
        ),
        (
            "dynamic_factor",
            "max dynamic mesh force / static",
            vec![
                ("up-sweep".to_string(), curve(&up, &|p| p.dynamic_factor)),
                (
                    "down-sweep".to_string(),
                    curve(&down, &|p| p.dynamic_factor),
                ),
            ],
        ),
        (
            "harmonics",
            "DTE amplitude at mesh harmonic [um]",
            (0..geardyn::sweep::HARMONICS)
                .map(|h| {
                    (
                        format!("order {} x z1", h + 1),
                        curve(&up, &|p| p.harmonics[h] * 1e6),
                    )
                })
                .collect(),
        ),
        (
            "stability",
            "largest Floquet multiplier |lambda| (> 1 unstable)",
            vec![("max |lambda|".to_string(), curve(&up, &|p| p.floquet))],
        ),
    ];
    for (stem, label, series) in plots {
        let plot = report::plot::LinePlot {
            title: format!(
                "{}: {stem}, stiffness {source_name}, zeta = {damping_ratio}",
                case.name()
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: label.into(),
            series,
        };
        report::plot::save_chart(&dir, stem, &plot)?;
    }

    // Waterfall: DTE amplitude at each mesh harmonic, at its frequency, over speed.
    let step_rpm = if rpms.len() > 1 {
        rpms[1] - rpms[0]
    } else {
        1.0
    };
    let mesh_hz_per_rpm = pair.gears[0].teeth() as f64 / 60.0;
    let waterfall = report::plot::ColourMap {
        title: format!(
            "{}: DTE mesh harmonics (log colour, 3 decades), stiffness {source_name}",
            case.name()
        ),
        x_label: "driver speed [rpm]".into(),
        y_label: "frequency [Hz]".into(),
        cells: up
            .iter()
            .flat_map(|p| {
                p.harmonics.iter().enumerate().map(move |(h, a)| {
                    (p.driver_speed_rpm, (h + 1) as f64 * p.mesh_frequency_hz, *a)
                })
            })
            .collect(),
        cell_size: (
            step_rpm,
            0.8 * step_rpm * mesh_hz_per_rpm * geardyn::sweep::HARMONICS as f64,
        ),
        decades: 3.0,
    };
    report::plot::save_chart(&dir, "waterfall", &waterfall)?;
    if let Some(duration) = run_up_s {
        if !(duration > 0.0 && duration.is_finite()) {
            anyhow::bail!("--run-up-s {duration} is invalid: give a duration > 0 in seconds");
        }
        let to_speed = |rpm: f64| rpm * 2.0 * std::f64::consts::PI / 60.0;
        let (from, to) = (rpms[0], rpms[rpms.len() - 1]);
        let r = geardyn::lumped::run_up(&model, to_speed(from), to_speed(to), duration, 200_000);
        let static_x = model.force / model.stiffness.mean();
        let rows = (0..r.time.len()).map(|i| {
            vec![
                format!("{:.9}", r.time[i]),
                format!(
                    "{:.4}",
                    r.driver_speed[i] * 60.0 / (2.0 * std::f64::consts::PI)
                ),
                format!("{:.6}", (r.displacement[i] - static_x) * 1e6),
                format!("{:.4}", r.mesh_force[i]),
            ]
        });
        report::write_csv(
            &dir.join("runup.csv"),
            &[
                "time_s",
                "driver_rpm",
                "dte_about_static_um",
                "mesh_force_n",
            ],
            rows,
        )
        .context("cannot write runup.csv")?;
        let plot = report::plot::LinePlot {
            title: format!(
                "{}: run-up {from:.0} -> {to:.0} rpm in {duration} s, stiffness {source_name}",
                case.name()
            ),
            x_label: "driver speed [rpm]".into(),
            y_label: "DTE about the static deflection [um]".into(),
            series: vec![(
                "run-up".into(),
                (0..r.time.len())
                    .step_by((r.time.len() / 20_000).max(1))
                    .map(|i| {
                        (
                            r.driver_speed[i] * 60.0 / (2.0 * std::f64::consts::PI),
                            (r.displacement[i] - static_x) * 1e6,
                        )
                    })
                    .collect(),
            )],
        };
        report::plot::save_chart(&dir, "runup", &plot)?;
        println!(
            "run-up: {} RK4 steps, {} samples in runup.csv",
            r.steps,
            r.time.len()
        );
    }
    let rms: Vec<f64> = up.iter().map(|p| p.dte_rms).collect();
    let resonance_rpm = geardyn::sweep::peaks(&rpms, &rms);
    // The primary resonance: the response peak nearest f_mesh = f_n.
    let primary_rpm = fn_hz * 60.0 / pair.gears[0].teeth() as f64;
    let primary = resonance_rpm
        .iter()
        .copied()
        .min_by(|a, b| (a - primary_rpm).abs().total_cmp(&(b - primary_rpm).abs()));
    let mut separation_ranges: Vec<(f64, f64)> = Vec::new();
    for p in &up {
        if p.separated {
            match separation_ranges.last_mut() {
                Some(r) if (p.driver_speed_rpm - r.1) <= (rpms[1] - rpms[0]) * 1.0001 => {
                    r.1 = p.driver_speed_rpm
                }
                _ => separation_ranges.push((p.driver_speed_rpm, p.driver_speed_rpm)),
            }
        }
    }
    // The strongest spectral lines over the whole up-sweep.
    let mut strongest: Vec<serde_json::Value> = up
        .iter()
        .flat_map(|p| {
            p.peaks.iter().map(move |(hz, a)| {
                serde_json::json!({"driver_rpm": p.driver_speed_rpm, "frequency_hz": hz, "amplitude_um": a * 1e6})
            })
        })
        .collect();
    strongest.sort_by(|a, b| {
        b["amplitude_um"]
            .as_f64()
            .unwrap_or(0.0)
            .total_cmp(&a["amplitude_um"].as_f64().unwrap_or(0.0))
    });
    strongest.truncate(10);
    let summary = serde_json::json!({
        "case": case.name(),
        "stiffness_source": source_name,
        "drive": drive,
        "mean_stiffness_n_per_m": model.stiffness.mean(),
        "modes_hz": mode_frequencies_hz(&model),
        "effective_mass_kg": effective_mass,
        "inertia_kg_mm2": [i1 * 1e6, i2 * 1e6],
        "natural_frequency_hz": fn_hz,
        "damping_ratio": damping_ratio,
        "torque_nm": torque,
        "primary_resonance_rpm": primary,
        "resonance_rpm": resonance_rpm,
        "max_dynamic_factor": up.iter().chain(&down).map(|p| p.dynamic_factor).fold(0.0, f64::max),
        "separation_rpm_ranges": separation_ranges,
        "unstable_rpm": up.iter().filter(|p| p.floquet > 1.0).map(|p| p.driver_speed_rpm).collect::<Vec<_>>(),
        "points": rpms.len(),
        "all_converged": up.iter().chain(&down).all(|p| p.converged),
        "wall_s": wall_s,
        "stiffness_wall_s": stiffness_wall_s,
        "total_wall_s": started.elapsed().as_secs_f64(),
        "strongest_peaks": strongest,
        "model": model_note,
    });
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;
    println!(
        "{} points in {:.2} s (stiffness {:.2} s); resonances at {} rpm; primary {} rpm (f_mesh = f_n at {:.0} rpm); max dynamic factor {:.3}",
        rpms.len(),
        wall_s,
        stiffness_wall_s,
        summary["resonance_rpm"],
        primary.map_or("none".into(), |r| format!("{r:.0}")),
        primary_rpm,
        summary["max_dynamic_factor"].as_f64().unwrap_or(f64::NAN)
    );
    println!("wrote {}", dir.display());
    Ok(())
}

fn stability(args: &CommonArgs, rpm: &str, options: &LumpedArgs) -> Result<()> {
    let setup = lumped_setup(args, rpm, options)?;
    let LumpedSetup {
        case,
        rpms,
        model,
        source_name,
        fn_hz,
        damping_ratio,
        ..
    } = &setup;
    let dir = output_dir(args.out.as_deref(), "stability", case)?;
    report::write_atomic(&dir.join("case.toml"), case.text.as_bytes())
        .context("cannot write case.toml")?;
    let started = std::time::Instant::now();
    let multipliers = geardyn::sweep::floquet_map(model, rpms);
    let wall_s = started.elapsed().as_secs_f64();
    let z1 = case.pair.gears[0].teeth() as f64;
    let rows = rpms.iter().zip(&multipliers).map(|(r, m)| {
        vec![
            format!("{r:.3}"),
            format!("{:.3}", r / 60.0 * z1),
            format!("{m:.8}"),
        ]
    });
    report::write_csv(
        &dir.join("stability.csv"),
        &["driver_rpm", "mesh_hz", "floquet_max_multiplier"],
        rows,
    )
    .context("cannot write stability.csv")?;
    let mut ranges: Vec<(f64, f64)> = Vec::new();
    for (i, m) in multipliers.iter().enumerate() {
        if *m > 1.0 {
            match ranges.last_mut() {
                Some(range) if i > 0 && multipliers[i - 1] > 1.0 => range.1 = rpms[i],
                _ => ranges.push((rpms[i], rpms[i])),
            }
        }
    }
    // Principal parametric regions of a cosine stiffness: f_mesh ≈ 2 f_i / j for each mode i.
    let modes_hz = mode_frequencies_hz(model);
    let theory: Vec<f64> = modes_hz
        .iter()
        .flat_map(|f| (1..=3).map(move |j| 2.0 * f / j as f64 * 60.0 / z1))
        .collect();
    let plot = report::plot::LinePlot {
        title: format!(
            "{}: Floquet stability, stiffness {source_name}, zeta = {damping_ratio}",
            case.name()
        ),
        x_label: "driver speed [rpm]".into(),
        y_label: "largest Floquet multiplier |lambda|".into(),
        series: vec![
            (
                "max |lambda|".into(),
                rpms.iter()
                    .copied()
                    .zip(multipliers.iter().copied())
                    .collect(),
            ),
            (
                "stability limit |lambda| = 1".into(),
                vec![(rpms[0], 1.0), (rpms[rpms.len() - 1], 1.0)],
            ),
        ],
    };
    report::plot::save_chart(&dir, "stability", &plot)?;
    let summary = serde_json::json!({
        "case": case.name(),
        "stiffness_source": source_name,
        "drive": setup.drive,
        "model": setup.model_note,
        "mean_stiffness_n_per_m": model.stiffness.mean(),
        "natural_frequency_hz": fn_hz,
        "modes_hz": modes_hz,
        "damping_ratio": damping_ratio,
        "unstable_rpm_ranges": ranges,
        "parametric_region_centres_rpm": theory,
        "max_multiplier": multipliers.iter().copied().fold(0.0, f64::max),
        "points": rpms.len(),
        "wall_s": wall_s,
        "stiffness_wall_s": setup.stiffness_wall_s,
    });
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;
    println!(
        "{} speeds in {:.3} s; unstable ranges {:?} rpm; principal regions expected near {:?} rpm; max |lambda| {:.4}",
        rpms.len(),
        wall_s,
        ranges,
        theory.iter().map(|r| r.round()).collect::<Vec<_>>(),
        summary["max_multiplier"].as_f64().unwrap_or(f64::NAN)
    );
    println!("wrote {}", dir.display());
    Ok(())
}

fn validate(study: &str, args: &CommonArgs, options: &LumpedArgs) -> Result<()> {
    use geardyn::lumped::{schemes, PeriodicTable};
    if study != "integrators" {
        anyhow::bail!("unknown study {study:?}: the studies are: integrators");
    }
    let setup = lumped_setup(args, "1000:2000:2", options)?;
    let case = &setup.case;
    if setup.model.bearings.is_some() {
        anyhow::bail!("the integrator study covers the 1-DOF model: drop --bearings (or bearings = true in the case)");
    }
    let dir = output_dir(args.out.as_deref(), "validate-integrators", case)?;
    let period = setup.model.stiffness.period;
    let k_mean = setup.model.stiffness.mean();
    let static_deflection = setup.model.force / k_mean;
    // Constant mean stiffness excited by a cosine TE: 0.2 × the static deflection stays in
    // contact; 2 × with 100 µm backlash separates every mesh period.
    let variant = |te_ratio: f64, backlash: Option<f64>| {
        let mut m = setup.model.clone();
        m.stiffness = PeriodicTable::constant(period, k_mean);
        m.unloaded_te = PeriodicTable::from_fn(period, 1 << 14, |t| {
            te_ratio * static_deflection * (std::f64::consts::TAU * t / period).cos()
        });
        m.backlash = backlash;
        m
    };
    let smooth = variant(0.2, None);
    let separating = variant(2.0, Some(100e-6));
    let speed = 0.7 * smooth.natural_frequency() * period / std::f64::consts::TAU;
    let started = std::time::Instant::now();
    let table = schemes::failure_table(&smooth, &separating, speed, 20);
    let wall_s = started.elapsed().as_secs_f64();
    let limit = |l: Option<f64>| {
        l.map_or("none (unconditionally stable)".to_string(), |v| {
            format!("{v:.6}")
        })
    };
    let header = [
        "scheme",
        "stability_limit_predicted_wh",
        "stability_limit_observed_wh",
        "accuracy_1pct_predicted_wh",
        "accuracy_1pct_observed_wh",
        "formal_order",
        "observed_order_smooth",
        "observed_order_separating",
        "error_smooth_32",
        "error_separating_32",
    ];
    let rows: Vec<Vec<String>> = table
        .iter()
        .map(|r| {
            vec![
                r.scheme.to_string(),
                limit(r.predicted_limit),
                limit(r.observed_limit),
                format!("{:.6}", r.predicted_accuracy_limit),
                format!("{:.6}", r.observed_accuracy_limit),
                format!("{:.1}", r.formal_order),
                format!("{:.3}", r.observed_order_smooth),
                format!("{:.3}", r.observed_order_separating),
                format!("{:.3e}", r.error_smooth),
                format!("{:.3e}", r.error_separating),
            ]
        })
        .collect();
    report::write_csv(&dir.join("integrators.csv"), &header, rows.clone())
        .context("cannot write integrators.csv")?;
    let mut markdown = format!(
        "| {} |\n|{}\n",
        header.join(" | "),
        "---|".repeat(header.len())
    );
    for row in &rows {
        markdown.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    report::write_atomic(&dir.join("integrators.md"), markdown.as_bytes())
        .context("cannot write integrators.md")?;
    let summary = serde_json::json!({
        "case": case.name(),
        "study": "integrators",
        "effective_mass_kg": setup.effective_mass,
        "mean_stiffness_n_per_m": k_mean,
        "natural_frequency_hz": setup.fn_hz,
        "damping_ratio": setup.damping_ratio,
        "mesh_frequency_over_natural": 0.7,
        "periods": 20,
        "errors": "end state after 20 mesh periods vs adaptive Dormand-Prince (tolerance 1e-11), in units of the static deflection, at 32 steps per natural period; orders are least-squares slopes over 16, 32, 64, 128 steps per natural period",
        "schemes": table,
        "wall_s": wall_s,
    });
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;
    print!("{markdown}");
    println!("wrote {}", dir.display());
    Ok(())
}

fn fe(args: &CommonArgs, options: &FeArgs) -> Result<()> {
    use geardyn::explicit::scene::{analyse_dte, prepare, run, statistics_start, FeSettings};
    use geardyn::report::fe as rep;
    use indicatif::{ProgressBar, ProgressStyle};
    let started = std::time::Instant::now();
    let case = load_case(args.case.as_deref())?;
    let rpm_to_speed = |rpm: f64| rpm * std::f64::consts::TAU / 60.0;
    let mut scene = match &options.scene {
        Some(name) => case
            .scene(name)
            .with_context(|| {
                format!(
                    "no scene {name:?} in the case; its scenes are: {:?}",
                    case.scenes
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                )
            })?
            .clone(),
        None => {
            let (Some(rpm), Some(duration)) = (options.speed_rpm, options.duration_s) else {
                anyhow::bail!(
                    "give --scene NAME (one of {:?}) or both --speed-rpm and --duration-s",
                    case.scenes
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                );
            };
            geardyn::case::Scene {
                name: format!("{rpm}rpm"),
                driver_speed: rpm_to_speed(rpm),
                torque: load_torque(&case, None)?,
                relief: case
                    .relief_variants
                    .first()
                    .context("the case has no relief variant")?
                    .name
                    .clone(),
                friction: 0.0,
                duration,
                ramp_time: (0.1 * duration).min(0.01),
            }
        }
    };
    if let Some(rpm) = options.speed_rpm {
        if !(rpm > 0.0 && rpm.is_finite()) {
            anyhow::bail!("--speed-rpm {rpm} is invalid: give a driver speed > 0");
        }
        scene.driver_speed = rpm_to_speed(rpm);
    }
    if let Some(duration) = options.duration_s {
        if !(duration > 0.0 && duration.is_finite()) {
            anyhow::bail!("--duration-s {duration} is invalid: give a simulated time > 0");
        }
        scene.duration = duration;
        scene.ramp_time = scene.ramp_time.min(0.5 * duration);
    }
    if let Some(ramp) = options.ramp_s {
        if !(ramp >= 0.0 && ramp < scene.duration) {
            anyhow::bail!(
                "--ramp-s {ramp} is invalid: give 0 ≤ ramp < the duration ({} s)",
                scene.duration
            );
        }
        scene.ramp_time = ramp;
    }
    if let Some(torque) = options.torque_nm {
        scene.torque = load_torque(&case, Some(torque))?;
    }
    if let Some(relief) = &options.relief {
        case.relief_variant(relief)
            .with_context(|| format!("no relief variant {relief:?} in the case"))?;
        scene.relief = relief.clone();
    }
    if let Some(mu) = options.friction {
        if !(0.0..1.0).contains(&mu) {
            anyhow::bail!("--friction {mu} is invalid: give a Coulomb coefficient in [0, 1)");
        }
        scene.friction = mu;
    }
    let mut settings = FeSettings::from_case(&case);
    if let Some(beta) = options.step_factor {
        if !(beta > 0.0 && beta <= 3.0) {
            anyhow::bail!(
                "--step-factor {beta} is invalid: give a value in (0, 3] (0.9 is safe; above 1 diverges)"
            );
        }
        settings.step_factor = beta;
    }
    if let Some(f) = options.penalty_factor {
        if !(f > 0.0 && f.is_finite()) {
            anyhow::bail!("--penalty-factor {f} is invalid: give a value > 0 (default 1)");
        }
        settings.penalty_factor = f;
    }
    if let Some(lumping) = options.mass_lumping {
        settings.mass_lumping = lumping;
    }
    if let Some(zeta) = options.mesh_damping_ratio {
        if !(0.0..1.0).contains(&zeta) {
            anyhow::bail!(
                "--mesh-damping-ratio {zeta} is invalid: give a ratio in [0, 1) (default 0.05)"
            );
        }
        settings.mesh_damping_ratio = zeta;
    }
    if let Some(mm) = options.coarse_element_mm {
        let module = case.file.tool.module_mm;
        if !(mm > 0.0 && mm <= module) {
            anyhow::bail!(
                "--coarse-element-mm {mm} is invalid: give a size in (0, one module = {module}] mm"
            );
        }
        settings.coarse_size = mm * 1e-3;
    }
    if let Some(mm) = options.fine_element_mm {
        settings.fine_size = mm * 1e-3;
    }
    if !(settings.fine_size > 0.0 && settings.fine_size <= settings.coarse_size) {
        anyhow::bail!(
            "the explicit flank element size {} mm is invalid: give a size in (0, the coarse size = {} mm] (--fine-element-mm, --coarse-element-mm)",
            settings.fine_size * 1e3,
            settings.coarse_size * 1e3
        );
    }
    let dir = output_dir(args.out.as_deref(), &format!("fe-{}", scene.name), &case)?;
    report::write_atomic(&dir.join("case.toml"), case.text.as_bytes())
        .context("cannot write case.toml")?;
    eprintln!(
        "scene {}: {:.1} rpm, {} N·m, relief {}, mu {}, {} s (ramp {} s); meshing and measuring the critical step ...",
        scene.name,
        scene.driver_speed * 60.0 / std::f64::consts::TAU,
        scene.torque,
        scene.relief,
        scene.friction,
        scene.duration,
        scene.ramp_time
    );
    let prepared = prepare(&case, &scene, &settings)?;
    let total_steps = (scene.duration / prepared.dt).ceil();
    println!(
        "{} elements ({} tooth pairs, flank elements {:.2} mm, body {:.2} mm); dt_cr = {:.4e} s (bodies {:.4e} / {:.4e}, contact {:.4e}; paper's L/c {:.4e}), dt = {:.4e} s, {} steps",
        prepared.model.elements(),
        prepared.model.tooth_pairs.len(),
        settings.fine_size * 1e3,
        settings.coarse_size * 1e3,
        prepared.dt_critical,
        prepared.dt_bodies[0],
        prepared.dt_bodies[1],
        prepared.dt_contact,
        prepared.dt_paper,
        prepared.dt,
        total_steps
    );
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template(
            "explicit FE [{bar:40}] {percent}% elapsed {elapsed}, ETA {eta}",
        )
        .expect("valid template"),
    );
    // Without a terminal (a log file, CI) the bar is hidden: a line every 10 % instead.
    let plain_log = bar.is_hidden();
    let started_loop = std::time::Instant::now();
    let mut logged = 0;
    let outcome = run(
        &prepared,
        scene.duration,
        settings.output_interval,
        &mut |f| {
            bar.set_position((f * 1000.0) as u64);
            let tenth = (f * 10.0).floor() as usize;
            if plain_log && tenth > logged {
                logged = tenth;
                let elapsed = started_loop.elapsed().as_secs_f64();
                eprintln!(
                    "explicit FE {:3.0} % after {:.0} s, about {:.0} s to go",
                    f * 100.0,
                    elapsed,
                    elapsed * (1.0 - f) / f.max(1e-9)
                );
            }
        },
    );
    bar.finish_and_clear();
    let history = &outcome.history;
    let stats_start = statistics_start(&prepared, &scene);
    let analysis = analyse_dte(history, &prepared.model, scene.torque, stats_start);
    let derived = rep::derive(history);
    let spectrum = rep::dte_spectrum(history, stats_start);
    let mesh_hz = scene.driver_speed / case.pair.gears[0].angular_pitch();
    let peaks = rep::spectrum_peaks(&spectrum, 0.5 * mesh_hz, 8);
    let pair_names: Vec<String> = prepared
        .model
        .flank_pairs
        .iter()
        .map(|fp| fp.name())
        .collect();
    rep::write_history(&dir.join("history.csv"), history, &derived, &pair_names)
        .context("cannot write history.csv")?;
    report::write_csv(
        &dir.join("dte_spectrum.csv"),
        &["frequency_hz", "amplitude_rad"],
        spectrum
            .iter()
            .map(|(f, a)| vec![format!("{f:.4}"), format!("{a:.6e}")]),
    )
    .context("cannot write dte_spectrum.csv")?;
    if let Some(a) = &analysis {
        let angles: Vec<f64> = a.stiffness.iter().map(|p| p.0).collect();
        let values: Vec<f64> = a.stiffness.iter().map(|p| p.1).collect();
        report::stiffness_csv::write_stiffness_csv(
            &dir.join("stiffness.csv"),
            &angles,
            &values,
            &vec![0.0; angles.len()],
        )
        .context("cannot write stiffness.csv")?;
    }
    let title = format!("{}: {}", case.name(), scene.name);
    rep::plot_run(
        &dir,
        &title,
        history,
        &derived,
        &spectrum,
        analysis.as_ref(),
        &pair_names,
    )?;
    // The LTCA over the positions the statistics window covers: on the explicit run's mesh
    // (the same discretization) and on the case's mesh (the converged reference) when they differ.
    let ltca_on = |fine_mm: f64, coarse_mm: f64| -> anyhow::Result<Option<serde_json::Value>> {
        let mut ltca_case = case.clone();
        ltca_case.file.mesh.fine_element_mm = fine_mm;
        ltca_case.file.mesh.coarse_element_mm = coarse_mm;
        let variant = case.relief_variant(&scene.relief).expect("checked above");
        let model = ltca_model(&ltca_case, &variant.modifications)?;
        let results = model.run(64, scene.torque, &|_| {})?;
        Ok(analysis.as_ref().map(|a| {
            let pitch = case.pair.gears[0].angular_pitch();
            let start = history
                .time
                .iter()
                .position(|t| *t >= a.window.0)
                .unwrap_or(0);
            let covered: Vec<f64> = history.driver_rotation[start..]
                .iter()
                .map(|theta| {
                    let u = (theta / pitch).rem_euclid(1.0) * 64.0;
                    let i = (u.floor() as usize).min(63);
                    let f = u - i as f64;
                    results[i].ste * (1.0 - f) + results[(i + 1) % 64].ste * f
                })
                .collect();
            let mean = covered.iter().sum::<f64>() / covered.len() as f64;
            let (min, max) = covered
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(*v), hi.max(*v))
                });
            let k_mean = results.iter().map(|r| r.mesh_stiffness).sum::<f64>() / 64.0;
            serde_json::json!({
                "fine_element_mm": fine_mm,
                "coarse_element_mm": coarse_mm,
                "ste_mean_rad": mean,
                "ste_max_rad": max,
                "ste_min_rad": min,
                "ste_peak_to_peak_rad": max - min,
                "mesh_stiffness_mean_n_per_m": k_mean,
                "dte_over_ste_mean": a.dte_mean_rad / mean,
                "dte_over_ste_peak_to_peak": a.dte_peak_to_peak_rad / (max - min),
                "dte_lowpass_over_ste_mean": a.lowpass.map(|l| l.mean_rad / mean),
                "dte_lowpass_over_ste_peak_to_peak": a.lowpass.map(|l| l.peak_to_peak_rad / (max - min)),
            })
        }))
    };
    let (fine_mm, coarse_mm) = (settings.fine_size * 1e3, settings.coarse_size * 1e3);
    let ltca_same = ltca_on(fine_mm, coarse_mm)?;
    let case_mesh = (
        case.file.mesh.fine_element_mm,
        case.file.mesh.coarse_element_mm,
    );
    let ltca_case_mesh =
        if (case_mesh.0 - fine_mm).abs() > 1e-9 || (case_mesh.1 - coarse_mm).abs() > 1e-9 {
            ltca_on(case_mesh.0, case_mesh.1)?
        } else {
            ltca_same.clone()
        };
    let field = |v: &Option<serde_json::Value>, key: &str| v.as_ref().and_then(|v| v[key].as_f64());
    let final_energy = outcome.final_energy;
    let max_work = history
        .energy
        .iter()
        .map(|e| e.external_work.abs())
        .fold(0.0, f64::max);
    let max_balance = history
        .energy
        .iter()
        .map(|e| e.balance().abs())
        .fold(0.0, f64::max);
    let energy_error_rel = if max_work > 0.0 {
        max_balance / max_work
    } else {
        0.0
    };
    let transmitted = history.energy.last().map_or(0.0, |e| e.transmitted_work);
    let energy_error_rel_transmitted = if transmitted > 0.0 {
        max_balance / transmitted
    } else {
        0.0
    };
    let ns_per_element_step =
        outcome.wall_s * 1e9 / (outcome.steps.max(1) as f64 * prepared.model.elements() as f64);
    let get = |f: &dyn Fn(&geardyn::explicit::scene::DteAnalysis) -> f64| analysis.as_ref().map(f);
    let mut summary = serde_json::json!({
        "case": case.name(),
        "scene": scene,
        "dte_mean_rad": get(&|a| a.dte_mean_rad),
        "dte_max_rad": get(&|a| a.dte_max_rad),
        "dte_min_rad": get(&|a| a.dte_min_rad),
        "dte_peak_to_peak_rad": get(&|a| a.dte_peak_to_peak_rad),
        "mesh_stiffness_mean_n_per_m": get(&|a| a.mesh_stiffness_mean_n_per_m),
        "mesh_stiffness_from_mean_dte_n_per_m": get(&|a| a.mesh_stiffness_from_mean_dte_n_per_m),
        "stiffness_pitch_coverage": get(&|a| a.pitch_coverage),
        "stats_window_s": analysis.as_ref().map(|a| [a.window.0, a.window.1]),
        "dte_lowpass": analysis.as_ref().and_then(|a| a.lowpass),
        "ltca_ste_mean_rad_same_positions": field(&ltca_same, "ste_mean_rad"),
        "ltca_mesh_stiffness_mean_n_per_m": field(&ltca_same, "mesh_stiffness_mean_n_per_m"),
        "dte_over_ltca_mean": field(&ltca_same, "dte_over_ste_mean"),
        "ltca_same_mesh": ltca_same,
        "ltca_case_mesh": ltca_case_mesh,
        "mesh_frequency_hz": mesh_hz,
        "dte_spectrum_peaks": peaks.iter().map(|(f, a)| serde_json::json!({"frequency_hz": f, "amplitude_rad": a})).collect::<Vec<_>>(),
        "contact_force_max_n": history.force_total.iter().copied().fold(0.0, f64::max),
        "impact_d1_max_n": derived.force_detail.iter().map(|v| v.abs()).fold(0.0, f64::max),
        "energy": final_energy,
        "energy_error_rel": energy_error_rel,
        "energy_error_rel_transmitted": energy_error_rel_transmitted,
        "steps": outcome.steps,
        "ns_per_element_step": ns_per_element_step,
        "wall_s": outcome.wall_s,
        "total_wall_s": started.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
        "diverged": outcome.diverged,
        "dt_critical_coupled_s": outcome.coupled_steps.iter().map(|c| c.dt_critical_s).reduce(f64::min),
        "dt_critical_coupled_checks": outcome.coupled_steps,
        "model": format!(
            "2D {} ({} plane), corotational 8-node quadrilaterals, lumped mass ({}); rigid hubs, rigid bearings; driver at prescribed speed, driven hub with load torque and a mesh dashpot (zeta {:.3}) on the DTE rate; segment-to-segment penalty contact (two-pass, 4 Gauss points per edge and the tip corner) with Coulomb friction on drive and back flanks of {} tooth pairs; fine flank elements {:.2} mm only on the teeth that engage during the scene, {:.2} mm elsewhere",
            if case.file.fe.plane == geardyn::fe::PlaneState::Strain { "plane strain" } else { "plane stress" },
            case.pair.gears[0].spec.face_width * 1e3,
            match settings.mass_lumping {
                MassLumping::CornerTwelfth => "corners 1/12, mid-sides 1/6 of each element's mass",
                MassLumping::Hrz => "HRZ diagonal scaling",
            },
            settings.mesh_damping_ratio,
            prepared.model.tooth_pairs.len(),
            settings.fine_size * 1e3,
            settings.coarse_size * 1e3
        ),
    });
    if let Some(map) = summary.as_object_mut() {
        map.extend(
            rep::step_summary(&prepared)
                .as_object()
                .cloned()
                .unwrap_or_default(),
        );
        map.insert("penalty_factor".into(), settings.penalty_factor.into());
        map.insert("step_factor".into(), settings.step_factor.into());
        map.insert(
            "mass_lumping".into(),
            serde_json::to_value(settings.mass_lumping).unwrap_or_default(),
        );
        map.insert(
            "mesh_damping_ratio".into(),
            settings.mesh_damping_ratio.into(),
        );
        map.insert("fine_element_mm".into(), (settings.fine_size * 1e3).into());
        map.insert(
            "coarse_element_mm".into(),
            (settings.coarse_size * 1e3).into(),
        );
    }
    report::write_json(&dir.join("summary.json"), &summary).context("cannot write summary.json")?;
    if let Some(message) = &outcome.diverged {
        anyhow::bail!("{message}; partial results in {}", dir.display());
    }
    println!(
        "{} steps in {:.1} s ({:.1} ns per element-step on {} threads); DTE mean {:.4e} rad (LTCA at the same positions: {:.4e} on this mesh, {:.4e} on the case's), peak-to-peak {:.4e} rad (LTCA {:.4e}, {:.4e}); k mean {:.4e} N/m; energy error {:.2e} of the net work, {:.2e} of the transmitted work",
        outcome.steps,
        outcome.wall_s,
        ns_per_element_step,
        rayon::current_num_threads(),
        summary["dte_mean_rad"].as_f64().unwrap_or(f64::NAN),
        field(&ltca_same, "ste_mean_rad").unwrap_or(f64::NAN),
        field(&ltca_case_mesh, "ste_mean_rad").unwrap_or(f64::NAN),
        summary["dte_peak_to_peak_rad"].as_f64().unwrap_or(f64::NAN),
        field(&ltca_same, "ste_peak_to_peak_rad").unwrap_or(f64::NAN),
        field(&ltca_case_mesh, "ste_peak_to_peak_rad").unwrap_or(f64::NAN),
        summary["mesh_stiffness_mean_n_per_m"].as_f64().unwrap_or(f64::NAN),
        energy_error_rel,
        energy_error_rel_transmitted
    );
    if let Some(coupled) = summary["dt_critical_coupled_s"].as_f64() {
        println!(
            "stable step where the contact was (bodies and penalty springs, power iteration at {} instants): {coupled:.4e} s at the least, {:.2} x the step used",
            outcome.coupled_steps.len(),
            coupled / prepared.dt
        );
    }
    println!("wrote {}", dir.display());
    Ok(())
}

/// Undamped natural frequencies of the lumped model at the mean mesh stiffness [Hz].
fn mode_frequencies_hz(model: &geardyn::lumped::MeshModel) -> Vec<f64> {
    model
        .mode_frequencies(model.stiffness.mean())
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect()
}

fn print_case(path: Option<&Path>) -> Result<()> {
    match path {
        Some(p) => {
            let case = Case::load(p)?;
            print!("{}", case.text);
        }
        None => print!("{EMBEDDED_DEFAULT}"),
    }
    Ok(())
}
