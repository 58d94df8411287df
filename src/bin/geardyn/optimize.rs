//! `geardyn optimize`: the relief optimization and its explicit-FE cross-check.

use super::*;

/// The case the optimization works on: the case file at `--torque-nm`.
pub fn optimize_case(args: &CommonArgs, options: &OptimizeArgs) -> Result<Case> {
    load(args, torque_overrides(options))
}

fn torque_overrides(options: &OptimizeArgs) -> Vec<Override> {
    study::torque_override(options.torque_nm)
        .into_iter()
        .collect()
}

pub fn optimize(args: &CommonArgs, options: &OptimizeArgs) -> Result<()> {
    let case = optimize_case(args, options)?;
    let dir = output_dir(args, "optimize", &case)?;
    let fe_check = options
        .fe_check_plan()
        .map(|plan| (dir.join("fe-check"), plan));
    optimize_into(args, options, &dir, fe_check)?;
    println!("wrote {}", dir.display());
    Ok(())
}

/// The relief optimization into `dir`, with the FE cross-check `fe_check` (its runs in
/// FE_ROOT/<candidate>-<scene>; a finished run of the same effective case there is reused; a
/// run that fails is a row with its reason, not the end of the check).
pub fn optimize_into(
    args: &CommonArgs,
    options: &OptimizeArgs,
    dir: &Path,
    fe_check: Option<(PathBuf, FeCheckPlan)>,
) -> Result<study::optimize::OptimizeStudy> {
    let case = optimize_case(args, options)?;
    let bar = staged_bar();
    let mut result = study::optimize::run(&case, &options.options(), &stage(&bar))?;
    bar.finish_and_clear();
    print!("{}", report::optimize::console(&result));
    report::optimize::write(OutputDir(dir), &case, &result)?;
    if let Some((root, plan)) = fe_check {
        let requests = fe_check_requests(args, options, &case, &result, &root, &plan)?;
        let outcomes = match super::executor::execute(
            args,
            &requests
                .iter()
                .map(|(_, _, r)| r.clone())
                .collect::<Vec<_>>(),
            &root.join("slurm"),
        ) {
            Ok(outcomes) => outcomes,
            Err(e) => {
                // --submit-only: the summary says where the cross-check stands.
                if let Some(submitted) = e.downcast_ref::<super::executor::Submitted>() {
                    result.summary.interrupted =
                        Some(format!("the FE cross-check is in the queue: {submitted}"));
                    OutputDir(dir).json("summary.json", &result.summary)?;
                }
                return Err(e);
            }
        };
        let mut runs: Vec<Option<study::optimize::CandidateRuns>> = result
            .candidates
            .iter()
            .map(|c| plan.includes(c).then_some([None, None]))
            .collect();
        for ((candidate, scene, request), outcome) in requests.iter().zip(outcomes) {
            let read = outcome.and_then(|_| report::optimize::read_fe_check_run(&request.dir));
            if let Some(scene_runs) = runs[*candidate].as_mut() {
                scene_runs[*scene] = Some(read);
            }
        }
        if geardyn::interrupt::stop_requested() {
            let message = format!(
                "the FE cross-check was interrupted; its finished runs in {} are taken as they are by the next run with the same --out",
                root.display()
            );
            result.summary.interrupted = Some(message.clone());
            OutputDir(dir).json("summary.json", &result.summary)?;
            anyhow::bail!(message);
        }
        let rb2 = case.pair.gears[1].base_radius;
        let check = study::optimize::fe_check(&result, &runs, rb2);
        print!(
            "{}",
            report::optimize::write_fe_check(OutputDir(dir), &check)?
        );
        result.summary.fe_check = Some(check);
        OutputDir(dir).json("summary.json", &result.summary)?;
    }
    let failures: Vec<String> = result
        .summary
        .starts
        .iter()
        .filter_map(|s| {
            let failure = s.failure.as_ref()?;
            Some(format!("{} from {}: {failure}", s.shape.name(), s.start))
        })
        .collect();
    let diverged: Vec<String> = result
        .candidates
        .iter()
        .filter_map(|c| Some(format!("{}: {}", c.name, c.sweep.diverged.as_ref()?)))
        .collect();
    if !diverged.is_empty() {
        anyhow::bail!(
            "the lumped sweeps of {} candidates diverged ({}); the optimization and every output \
             up to there are written to {}",
            diverged.len(),
            diverged.join("; "),
            dir.display()
        );
    }
    if !failures.is_empty() {
        anyhow::bail!(
            "the optimizer stopped early in {} of {} starts ({}); each keeps its last good design \
             and every output is written to {}. The cause is numerical: refine the LTCA \
             (mesh.fine_element_mm, --positions) or narrow the search (--max-relief-um)",
            failures.len(),
            result.summary.starts.len(),
            failures.join("; "),
            dir.display()
        );
    }
    Ok(result)
}

/// The cross-check's explicit runs of `result`'s candidates that `plan` includes, each with its
/// candidate's index and its scene's ([`study::optimize::FE_CHECK_SCENES`]), in
/// FE_ROOT/<candidate>-<scene>.
pub fn fe_check_requests(
    args: &CommonArgs,
    options: &OptimizeArgs,
    case: &geardyn::case::Case,
    result: &study::optimize::OptimizeStudy,
    root: &Path,
    plan: &FeCheckPlan,
) -> Result<Vec<(usize, usize, super::executor::FeRunRequest)>> {
    let names: Vec<&str> = result.candidates.iter().map(|c| c.name.as_str()).collect();
    if let Some(unknown) = plan
        .only
        .iter()
        .flatten()
        .find(|n| !names.contains(&n.as_str()))
    {
        anyhow::bail!(
            "--fe-check-only {unknown:?} is not a candidate; the candidates are {names:?}"
        );
    }
    let mut requests = Vec::new();
    for (index, candidate) in result.candidates.iter().enumerate() {
        if !plan.includes(candidate) {
            continue;
        }
        let mut overrides = torque_overrides(options);
        overrides.extend(study::optimize::fe_check_overrides(case, candidate)?);
        let with_relief = load(args, overrides)?;
        for (s, name) in study::optimize::FE_CHECK_SCENES.iter().enumerate() {
            if plan.scenes[s] {
                requests.push((
                    index,
                    s,
                    super::executor::FeRunRequest {
                        label: format!("fe-check {}", candidate.name),
                        case: with_relief.clone(),
                        scene: name.to_string(),
                        dir: root.join(format!("{}-{name}", candidate.name)),
                    },
                ));
            }
        }
    }
    // The speed scene's runs (several times a stiffness run's cost) first, so that runs side by
    // side end close together: the last to start is a short one.
    requests.sort_by_key(|(_, scene, _)| std::cmp::Reverse(*scene));
    Ok(requests)
}
