//! `geardyn plan <command> [args]`: the explicit FE runs a command would make, with their cost,
//! without running them. The lists are the ones the commands themselves execute.

use super::*;

use executor::FeRunRequest;

pub fn plan(words: Vec<String>) -> Result<()> {
    let cli = Cli::try_parse_from(std::iter::once("geardyn".to_string()).chain(words))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let requests = match &cli.command {
        Command::Run { common, full, .. } => run_requests(common, *full)?,
        Command::Compare { common, options } => {
            let case = load(common, Vec::new())?;
            let ask = options.ask();
            let dir = planned_dir(common, "compare");
            let given_rpm =
                study::compare::given_rpm_on_case_mesh(&case, &given_fe_runs(&options.fe_runs)?);
            ask.requests(common, &case, &dir, &given_rpm)?
        }
        Command::Optimize { common, options } => match options.fe_check_plan() {
            Some(check) => {
                let dir = planned_dir(common, "optimize");
                optimize_requests(common, options, &dir.join("fe-check"), &check)?
            }
            None => Vec::new(),
        },
        Command::Fe {
            common, options, ..
        } => {
            let base = load(common, Vec::new())?;
            let (overrides, scene) = study::fe::overrides(&base, options)?;
            let case = load(common, overrides)?;
            vec![FeRunRequest {
                label: format!("fe {scene}"),
                dir: planned_dir(common, &format!("fe-{scene}")),
                case,
                scene,
            }]
        }
        _ => Vec::new(),
    };
    // A folder two stages share is one run: the chain's stiffness run is the cross-check's
    // unmodified low-speed run, which finds it finished.
    let mut seen = std::collections::HashSet::new();
    let requests: Vec<FeRunRequest> = requests
        .into_iter()
        .filter(|r| seen.insert(r.dir.clone()))
        .collect();
    if requests.is_empty() {
        println!("this command makes no explicit FE run");
        return Ok(());
    }
    print!(
        "{}",
        study::cluster::plan_table(&executor::plan(&requests)?)
    );
    Ok(())
}

/// The command's --out, or the name its fresh folder would get (not created).
fn planned_dir(common: &CommonArgs, command: &str) -> PathBuf {
    common
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{command}-<case>-NNN")))
}

/// The relief optimization (no explicit FE) and its cross-check's runs.
fn optimize_requests(
    common: &CommonArgs,
    options: &OptimizeArgs,
    root: &Path,
    check: &FeCheckPlan,
) -> Result<Vec<FeRunRequest>> {
    let case = optimize::optimize_case(common, options)?;
    eprintln!("the relief optimization, to know its candidates (no explicit FE):");
    let bar = staged_bar();
    let result = study::optimize::run(&case, &options.options(), &stage(&bar))?;
    bar.finish_and_clear();
    Ok(
        optimize::fe_check_requests(common, options, &case, &result, root, check)?
            .into_iter()
            .map(|(_, _, r)| r)
            .collect(),
    )
}

/// Every explicit run of `geardyn run` (with `full`): the FE stiffness stage, the relief
/// cross-check and the comparison's speeds and sweep, in the chain's folders.
fn run_requests(common: &CommonArgs, full: bool) -> Result<Vec<FeRunRequest>> {
    let case = load(common, Vec::new())?;
    let dir = planned_dir(common, "run");
    let plan = study::run::RunPlan::new(full);
    let unmodified = study::unmodified_name(&case);
    let fe_root = dir.join("fe");
    let unmodified_case = load(common, study::optimize::unmodified_fe_overrides(&case))?;
    let stiffness_run = fe_root.join(study::optimize::fe_run_folder(
        &unmodified,
        study::compare::STIFFNESS_SCENE,
    ));
    let mut requests = vec![chain::stiffness_request(unmodified_case, &stiffness_run)];
    let sub = |name: &str| CommonArgs {
        out: Some(dir.join(name)),
        ..common.clone()
    };
    requests.extend(optimize_requests(
        &sub("optimize"),
        &OptimizeArgs::default_for_run(),
        &fe_root,
        &plan.fe_check,
    )?);
    let high_run = fe_root.join(study::optimize::fe_run_folder(
        &unmodified,
        study::compare::SPEED_SCENE,
    ));
    let given: Vec<PathBuf> = plan
        .compare_high_speed_run
        .then_some(high_run.clone())
        .into_iter()
        .collect();
    let stiffness_csv = stiffness_run.join("stiffness.csv");
    let ask = chain::compare_ask(&case, &plan, &given, &stiffness_csv)?;
    // The cross-check's high-speed run is planned above; the comparison takes it as given.
    let given_rpm: Vec<f64> = match plan.compare_high_speed_run {
        true => case
            .scene(study::compare::SPEED_SCENE)
            .map(|s| s.driver_speed * 60.0 / std::f64::consts::TAU)
            .into_iter()
            .collect(),
        false => Vec::new(),
    };
    let compare_requests = ask.requests(common, &case, &dir.join("compare"), &given_rpm)?;
    requests.extend(compare_requests);
    Ok(requests)
}
