//! The lumped model's commands: `geardyn sweep` (with its checkpoint and --resume) and
//! `geardyn stability`.

use super::*;

/// The case with the lumped flags applied.
pub fn lumped_case(args: &CommonArgs, options: &LumpedShorthands) -> Result<Case> {
    let case = load(args, options.overrides()?)?;
    if case.lumped.stiffness == StiffnessSource::Ltca {
        eprintln!("computing the LTCA stiffness ...");
    }
    Ok(case)
}

pub fn sweep(
    args: &CommonArgs,
    rpm: RpmRange,
    options: &LumpedShorthands,
    run_up_s: Option<f64>,
    resume: bool,
) -> Result<()> {
    let case = lumped_case(args, options)?;
    let checkpoint_file = "sweep_checkpoint.json";
    let resume = match (&args.out, resume) {
        (None, true) => anyhow::bail!("--resume needs --out DIR, the interrupted sweep's folder"),
        (Some(dir), true) => {
            let path = dir.join(checkpoint_file);
            let text = std::fs::read_to_string(&path).with_context(|| {
                format!(
                    "cannot read {}: is {} an interrupted sweep's folder?",
                    path.display(),
                    dir.display()
                )
            })?;
            let checkpoint: study::sweep::SweepCheckpoint = serde_json::from_str(&text)
                .with_context(|| format!("{} is not a sweep checkpoint", path.display()))?;
            eprintln!("resuming: {}", checkpoint.describe());
            Some(checkpoint)
        }
        (_, false) => None,
    };
    let options = study::sweep::SweepOptions {
        rpm,
        run_up_s,
        resume,
    };
    eprintln!(
        "sweeping {} speeds up and down (Ctrl-C stops and keeps the points for --resume) ...",
        options.rpm.0.len()
    );
    let outcome = study::sweep::run(&case, &options)?;
    let dir = output_dir(args, "sweep", &case)?;
    let out = OutputDir(&dir);
    // A sweep that stopped early keeps its points in the checkpoint, and its summary says why.
    let stopped = |checkpoint: &study::sweep::SweepCheckpoint,
                   interrupted: Option<String>,
                   diverged: Option<String>|
     -> Result<()> {
        out.case(&case)?;
        out.json(checkpoint_file, checkpoint)?;
        let resume = interrupted.as_ref().map(|_| {
            format!(
                "geardyn sweep ... --resume --out {} (the same case, --set and --rpm)",
                dir.display()
            )
        });
        out.json(
            "summary.json",
            &study::StoppedEarly {
                case: case.name().to_string(),
                command: "sweep".into(),
                interrupted,
                diverged,
                resume,
            },
        )?;
        Ok(())
    };
    let result = match outcome {
        study::sweep::SweepRun::Done(result) => result,
        study::sweep::SweepRun::Interrupted(checkpoint) => {
            let message = checkpoint.describe();
            stopped(&checkpoint, Some(message.clone()), None)?;
            anyhow::bail!(
                "sweep {message}; its points are kept in {}: add --resume --out {} to continue",
                dir.join(checkpoint_file).display(),
                dir.display()
            );
        }
        study::sweep::SweepRun::Diverged(checkpoint) => {
            let divergence = checkpoint.progress.diverged.as_ref().expect("diverged");
            let message = format!("{divergence}; {}", checkpoint.describe());
            stopped(&checkpoint, None, Some(message.clone()))?;
            anyhow::bail!(
                "{message}. The points swept before it are in {}",
                dir.join(checkpoint_file).display()
            );
        }
    };
    print!("{}", report::lumped::setup_console(&result.setup));
    report::lumped::write_sweep(out, &case, &result)?;
    out.remove(checkpoint_file)?;
    print!("{}", report::lumped::sweep_console(&result));
    println!("wrote {}", dir.display());
    if let Some(message) = &result.summary.run_up_diverged {
        anyhow::bail!("{message}");
    }
    Ok(())
}

pub fn stability(args: &CommonArgs, rpm: &RpmRange, options: &LumpedShorthands) -> Result<()> {
    let case = lumped_case(args, options)?;
    let result = study::stability::run(&case, rpm)?;
    print!("{}", report::lumped::setup_console(&result.setup));
    let dir = output_dir(args, "stability", &case)?;
    report::lumped::write_stability(OutputDir(&dir), &case, &result)?;
    print!("{}", report::lumped::stability_console(&result));
    println!("wrote {}", dir.display());
    Ok(())
}
