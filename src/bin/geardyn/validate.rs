//! `geardyn validate STUDY`: the quick set, the generated-case property check, the lumped
//! integrators' failure table and the explicit FE's mass scaling.

use super::*;

pub fn validate_quick(args: &CommonArgs) -> Result<()> {
    let case = load(args, Vec::new())?;
    let dir = output_dir(args, "validate-quick", &case)?;
    let bar = staged_bar();
    let result = study::quick_validation::run(&case, &stage(&bar))?;
    bar.finish_and_clear();
    print!(
        "{}",
        report::quick_validation::write(OutputDir(&dir), &result)?
    );
    println!("wrote {}", dir.display());
    if result.failed > 0 {
        anyhow::bail!(
            "{} of {} validation checks broke their tolerance (checks.md in {})",
            result.failed,
            result.checks.len(),
            dir.display()
        );
    }
    Ok(())
}

pub fn validate_properties(args: &CommonArgs, cases: usize, seed: u64) -> Result<()> {
    let case = load(args, Vec::new())?;
    if args.case.is_some() || !args.set.is_empty() {
        anyhow::bail!(
            "validate properties generates its cases from the embedded one: give no case file or --set"
        );
    }
    let dir = output_dir(args, "validate-properties", &case)?;
    let bar = staged_bar();
    // The samples' panics are caught and counted; their messages would only interleave.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = study::properties::run(cases, seed, &stage(&bar));
    std::panic::set_hook(hook);
    bar.finish_and_clear();
    OutputDir(&dir).json("summary.json", &result)?;
    println!(
        "{} generated cases in {:.0} s: {} valid, {} rejected with the parameter named; {} rejected \
         without it, {} with a NaN or infinite output, {} panicked; plausible-only cases valid: \
         {:.1} % of {}",
        result.cases,
        result.wall_s,
        result.valid,
        result.rejected,
        result.unnamed,
        result.not_finite,
        result.panicked,
        100.0 * result.plausible_valid_share,
        result.plausible_cases
    );
    for failure in &result.failures {
        println!(
            "  #{} {:?}: {:?}",
            failure.index, failure.changes, failure.outcome
        );
    }
    println!("wrote {}", dir.display());
    if !result.passed() {
        anyhow::bail!("the property check failed (failures above and in summary.json)");
    }
    Ok(())
}

pub fn validate_integrators(args: &CommonArgs, options: &LumpedShorthands) -> Result<()> {
    let case = lumped_case(args, options)?;
    let summary = study::validate::integrators(&case)?;
    let dir = output_dir(args, "validate-integrators", &case)?;
    print!(
        "{}",
        report::lumped::write_integrators(OutputDir(&dir), &summary)?
    );
    println!("wrote {}", dir.display());
    Ok(())
}

pub fn validate_frequencies(
    args: &CommonArgs,
    options: &LumpedShorthands,
    positions: usize,
) -> Result<()> {
    let case = lumped_case(args, options)?;
    let dir = output_dir(args, "validate-frequencies", &case)?;
    let bar = crate::progress::staged_bar();
    let result = study::frequencies::mesh_modes(&case, positions, &crate::progress::stage(&bar))?;
    bar.finish_and_clear();
    let table = report::lumped::write_mesh_modes(OutputDir(&dir), &case, &result)?;
    println!("{table}wrote {}", dir.display());
    if !(result.driver_held.pass && result.both_free.pass) {
        anyhow::bail!(
            "the lumped mesh mode is more than {:.0} % from the FE modal analysis (table above)",
            100.0 * study::frequencies::MESH_MODE_TOLERANCE
        );
    }
    Ok(())
}

pub fn validate_mass_scaling(args: &CommonArgs, scene: &str) -> Result<()> {
    let scaled = load(args, Vec::new())?;
    let dir = output_dir(args, "validate-mass-scaling", &scaled)?;
    let mut runs = vec![fe_run(
        &scaled,
        study::fe::scene(&scaled, scene)?,
        &dir.join("scaled"),
        false,
        &RunView::default(),
    )?];
    study::validate::check_scaled(&runs[0])?;
    // The unscaled run settles sooner, so a scene that covers a base pitch would end it
    // sooner: both over the scaled run's duration, for one window.
    let unscaled = load(
        args,
        vec![
            Override::set("fe.mass_scaling", false),
            Override::set(
                format!("scene[{scene}].duration_s"),
                runs[0].summary.scene.duration,
            ),
            Override::set(format!("scene[{scene}].cover_pitch"), false),
        ],
    )?;
    runs.push(fe_run(
        &unscaled,
        study::fe::scene(&unscaled, scene)?,
        &dir.join("unscaled"),
        false,
        &RunView::default(),
    )?);
    let result = study::validate::mass_scaling(scaled.name(), &scaled.pair, &runs[0], &runs[1])?;
    let table = report::fe::write_mass_scaling(OutputDir(&dir), &scaled, &result)?;
    println!("{table}wrote {}", dir.display());
    Ok(())
}

pub fn validate_pairs(
    args: &CommonArgs,
    only: &[String],
    with_fe: bool,
    with_run: bool,
) -> Result<()> {
    if args.case.is_some() || !args.set.is_empty() {
        anyhow::bail!(
            "validate pairs runs its own matrix of pairs (geardyn::samples::PAIR_MATRIX): give no case file or --set; choose pairs with --only"
        );
    }
    let names: Vec<&str> = geardyn::samples::PAIR_MATRIX
        .iter()
        .map(|p| p.name)
        .collect();
    for name in only {
        anyhow::ensure!(
            names.contains(&name.as_str()),
            "--only {name}: no such pair; the matrix has {}",
            names.join(", ")
        );
    }
    let pairs: Vec<_> = geardyn::samples::PAIR_MATRIX
        .iter()
        .filter(|p| only.is_empty() || only.iter().any(|o| o == p.name))
        .collect();
    let base = load(args, Vec::new())?;
    let dir = output_dir(args, "validate-pairs", &base)?;
    let started = std::time::Instant::now();
    let bar = staged_bar();
    let mut rows = Vec::new();
    for pair in pairs {
        // A stop request (Ctrl-C, SIGTERM) ends the matrix after the row it came in; the table
        // of the rows done is written below.
        if geardyn::interrupt::stop_requested() {
            bar.suspend(|| eprintln!("stopped on request before pair {}", pair.name));
            break;
        }
        // A row that stops with an error (not periodic, a refused case) fails itself, not
        // the matrix.
        let mut row = match study::pairs::row(pair, &stage(&bar)) {
            Ok(row) => row,
            Err(error) => study::pairs::failed_row(pair, &error_text(&error.into())),
        };
        if with_fe && row.mesh_stiffness_mean_n_per_m.is_finite() {
            let case = pair.case()?;
            let scene = study::fe::scene(&case, "stiffness")?;
            bar.suspend(|| eprintln!("pair {}: the explicit FE's stiffness scene", pair.name));
            // A run that fails (diverged, or its own checks) fails the row, not the matrix.
            let run = fe_run(
                &case,
                scene,
                &dir.join(pair.name).join("fe-stiffness"),
                false,
                &RunView::default(),
            );
            study::pairs::add_fe(
                &mut row,
                run.as_ref().map(|r| &r.summary).map_err(crate::error_text),
            );
        }
        if with_run && row.mesh_stiffness_mean_n_per_m.is_finite() {
            bar.suspend(|| eprintln!("pair {}: geardyn run at coarse settings", pair.name));
            let outcome = bar.suspend(|| run_chain(pair, &dir.join(pair.name)));
            study::pairs::add_run(&mut row, outcome.map_err(|e| error_text(&e)));
        }
        bar.suspend(|| {
            eprintln!(
                "pair {}: {} ({:.0} s)",
                pair.name,
                if row.passed { "ok" } else { "FAILED" },
                row.wall_s
            );
            for check in row.checks.iter().filter(|c| !c.passed) {
                eprintln!("  {}", check.line());
            }
        });
        rows.push(row);
    }
    bar.finish_and_clear();
    let result = study::pairs::table(rows, started.elapsed().as_secs_f64());
    print!("{}", report::pairs::write(OutputDir(&dir), &result)?);
    println!("wrote {}", dir.display());
    anyhow::ensure!(
        !geardyn::interrupt::stop_requested(),
        "stopped on request after {} pairs; the table of those is in {}",
        result.rows.len(),
        dir.display()
    );
    anyhow::ensure!(
        result.failed == 0,
        "{} of {} pairs failed a check (pairs.md and checks.csv in {})",
        result.failed,
        result.rows.len(),
        dir.display()
    );
    Ok(())
}

/// The coarse settings `validate pairs --run` runs the chain at: the FE stiffness scene
/// shortened to 4 ms with a 2 ms ramp (a few mesh periods at its low speed, not lengthened to
/// a base pitch; the rest as the case gives it).
pub const RUN_COARSE_SETTINGS: [&str; 3] = [
    "scene[stiffness].duration_s=0.004",
    "scene[stiffness].ramp_s=0.002",
    "scene[stiffness].cover_pitch=false",
];

/// `geardyn run` on a matrix pair in `dir`/run (its case written to `dir`/case.toml): the
/// summary's self-check errors and warnings and its wall time.
fn run_chain(
    pair: &geardyn::samples::MatrixPair,
    dir: &std::path::Path,
) -> Result<study::pairs::RunOutcome> {
    let case = pair.case()?;
    std::fs::create_dir_all(dir)?;
    let path = dir.join("case.toml");
    std::fs::write(&path, &case.text)?;
    let args = CommonArgs {
        case: Some(path),
        out: Some(dir.join("run")),
        force: false,
        checkpoint_every_s: 600.0,
        executor: super::args::ExecutorArgs::default(),
        set: RUN_COARSE_SETTINGS
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()
            .map_err(|e| anyhow::anyhow!("{e}"))?,
    };
    let started = std::time::Instant::now();
    super::chain::run(&args, false, false)?;
    let text = std::fs::read_to_string(dir.join("run").join("summary.json"))?;
    let summary: serde_json::Value = serde_json::from_str(&text)?;
    let count = |key: &str| summary[key].as_u64().map(|n| n as usize);
    Ok(study::pairs::RunOutcome {
        self_check_errors: count("self_check_errors")
            .context("the run's summary has no self_check_errors")?,
        self_check_warnings: count("self_check_warnings").unwrap_or(0),
        wall_s: started.elapsed().as_secs_f64(),
    })
}
