//! Progress on the console: bars on a terminal, plain lines in a log; and the explicit FE run
//! every FE-driven command shares (prepare, run with progress, write, report divergence).

use std::path::Path;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

use geardyn::case::Case;
use geardyn::explicit::scene::Scene;
use geardyn::report::{self, OutputDir};
use geardyn::study;

/// How a run shows itself on the console: alone (its own bar, its lines as they are), or as one
/// of several at once (its label before each of its lines, its bar among theirs).
#[derive(Clone, Default)]
pub struct RunView {
    pub label: Option<String>,
    pub bars: Option<indicatif::MultiProgress>,
}

impl RunView {
    /// `text` with the label before each line.
    fn lines(&self, text: &str) -> String {
        match &self.label {
            None => text.to_string(),
            Some(label) => text.lines().map(|l| format!("[{label}] {l}\n")).collect(),
        }
    }

    /// Writes with the bars of the runs side by side taken off the terminal meanwhile (their
    /// redraw would overwrite what was written under them).
    fn write(&self, write: impl FnOnce()) {
        match &self.bars {
            Some(bars) => bars.suspend(write),
            None => write(),
        }
    }

    /// One line on stderr, labelled.
    fn say(&self, line: &str) {
        let text = self.lines(&format!("{line}\n"));
        self.write(|| eprint!("{text}"));
    }

    /// A block on stdout, labelled.
    fn print(&self, block: &str) {
        let text = self.lines(block);
        self.write(|| print!("{text}"));
    }
}

/// Prepares and runs an explicit scene with progress (a bar, or a line every 10 % without a
/// terminal) and writes it to `dir`; a diverged or interrupted run is written too, then reported
/// as an error. With `resume` it goes on from the checkpoint an interrupted run of the same
/// case left in `dir`.
pub fn fe_run(
    case: &Case,
    scene: &Scene,
    dir: &Path,
    resume: bool,
    view: &RunView,
) -> Result<study::fe::FeStudy> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let checkpoint = if resume {
        anyhow::ensure!(
            holds_case(case, dir, report::compare::fe_summary(dir).ok().as_ref()),
            "{} holds no run of this case (its case.toml differs or is missing, or its \
             summary names another fe.tooth_layout): resume with the same case file and --set \
             as the interrupted run",
            dir.display()
        );
        let checkpoint = report::fe::read_checkpoint(dir)?.with_context(|| {
            format!(
                "{} holds no checkpoint: its run was not interrupted, or it finished",
                dir.display()
            )
        })?;
        view.say(&format!(
            "resuming at step {} of {} ({:.0} s of wall time before)",
            checkpoint.0.next_step, checkpoint.0.total_steps, checkpoint.0.wall_s
        ));
        Some(checkpoint)
    } else {
        None
    };
    view.say(&report::fe::scene_line(scene));
    let prepared = study::fe::prepare(case, scene)?;
    view.print(&report::fe::prepared_console(case, &prepared, scene));
    // A resumed run is estimated on the steps it has left.
    let left = checkpoint.as_ref().map_or(1.0, |(c, _)| {
        1.0 - c.next_step.saturating_sub(1) as f64 / c.total_steps.max(1) as f64
    });
    let cost = study::fe::CostEstimate::of(&prepared, prepared.duration * left);
    let memory =
        geardyn::explicit::scene::run_memory(&prepared, prepared.duration, case.fe.output_interval);
    view.say(&format!(
        "estimated: {}; the run's history and state {}",
        cost.describe(),
        memory.describe()
    ));
    if cost.too_long() && !geardyn::resources::forced() {
        // Side by side the rate was timed on this run's share of the threads.
        let share = match view.bars {
            Some(_) => {
                " (timed on its share of the threads beside other runs: --jobs 1 gives it all)"
            }
            None => "",
        };
        anyhow::bail!(
            "the explicit run would take {}{share}, above the {} limit: coarsen the mesh \
             (--fine-element-mm, --coarse-element-mm), shorten the scene (--duration-s), or \
             add --force to run it anyway",
            study::fe::duration_words(cost.wall_s),
            study::fe::duration_words(study::fe::ESTIMATE_LIMIT_S)
        );
    }
    let template = "explicit FE [{bar:40}] {percent}% elapsed {elapsed}, ETA {eta}";
    let bar = match (&view.bars, &view.label) {
        // The label as the bar's prefix: a template would read its braces.
        (Some(bars), Some(label)) => {
            let bar = bars.add(progress_bar(&format!("{{prefix}}: {template}")));
            bar.set_prefix(label.clone());
            bar
        }
        _ => progress_bar(template),
    };
    bar.set_length(1000);
    // Without a terminal (a log file, CI) the bar is hidden: a line every 10 % instead.
    let plain_log = bar.is_hidden();
    let started = std::time::Instant::now();
    let mut logged = 0;
    // Case first, so a process killed before its end leaves a folder `--resume` accepts.
    OutputDir(dir).case(case)?;
    let checkpoint_path = dir.join(report::fe::CHECKPOINT);
    let mut keep = |checkpoint: &geardyn::explicit::scene::RunCheckpoint,
                    history: &geardyn::explicit::scene::History| {
        // A failed write loses only this checkpoint; the run goes on.
        if let Err(e) = report::fe::write_checkpoint(&checkpoint_path, checkpoint, history) {
            view.say(&format!(
                "could not keep a checkpoint in {}: {e}",
                checkpoint_path.display()
            ));
        }
    };
    let keeping = geardyn::explicit::scene::Keeping::every(checkpoint_every(), &mut keep);
    let result = study::fe::run(
        case,
        scene,
        &prepared,
        checkpoint,
        Some(keeping),
        &mut |f| {
            bar.set_position((f * 1000.0) as u64);
            let tenth = (f * 10.0).floor() as usize;
            if plain_log && tenth > logged {
                logged = tenth;
                let elapsed = started.elapsed().as_secs_f64();
                view.say(&format!(
                    "explicit FE {:3.0} % after {elapsed:.0} s, about {:.0} s to go",
                    f * 100.0,
                    elapsed * (1.0 - f) / f.max(1e-9)
                ));
            }
        },
    )?;
    bar.finish_and_clear();
    report::fe::write(OutputDir(dir), case, &result)?;
    if let Some(message) = result.summary.diverged.as_ref() {
        anyhow::bail!("{message}; partial results in {}", dir.display());
    }
    if let Some(message) = result.summary.interrupted.as_ref() {
        anyhow::bail!(
            "{message}; partial results in {dir}; go on with `geardyn fe ... --resume --out {dir}` \
             (the same case and flags), or `geardyn run --resume` for a run's stage",
            dir = dir.display()
        );
    }
    view.print(&report::fe::console(&result));
    let checks = &result.summary.self_checks;
    for check in checks.iter().filter(|c| !c.passed) {
        view.say(&check.line());
    }
    let errors = checks.iter().filter(|c| c.is_error()).count();
    if errors > 0 {
        anyhow::bail!(
            "{errors} of the run's checks against the LTCA on its own mesh failed (above); its \
             results are in {}",
            dir.display()
        );
    }
    Ok(result)
}

/// Runs scene `scene` of `case` into `dir`, unless `dir` holds a finished run of the same
/// effective case (its case.toml, compared as TOML values: comments and `--set` headers aside),
/// so an interrupted chain resumes; an interrupted run of the same case goes on from its
/// checkpoint. summary.json is written last, so a run is finished when it is there and has no
/// checkpoint; it is removed before a new run, so a stale one is never taken for the new case's.
pub fn fe_run_reusing(case: &Case, scene: &str, dir: &Path, view: &RunView) -> Result<()> {
    match run_state(case, dir) {
        RunState::Finished => {
            view.say(&format!("reusing the finished run in {}", dir.display()));
            return Ok(());
        }
        RunState::Interrupted => {
            return fe_run(case, study::fe::scene(case, scene)?, dir, true, view).map(|_| ());
        }
        RunState::Other => {}
    }
    match std::fs::remove_file(dir.join("summary.json")) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(e).with_context(|| format!("cannot clear {}", dir.display()))
        }
        _ => {}
    }
    fe_run(case, study::fe::scene(case, scene)?, dir, false, view).map(|_| ())
}

/// What an explicit run's folder holds for `case`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunState {
    /// A finished run of this case: its summary, read whole, and no checkpoint.
    Finished,
    /// An interrupted run of this case: its checkpoint.
    Interrupted,
    /// Nothing of this case: empty, another case's run, or a failed one.
    Other,
}

/// The folder's state from its case.toml, checkpoint and summary alone (summary.json is
/// written last): cheap enough for every poll of a queue, where reading each run's history
/// was not.
pub fn run_state(case: &Case, dir: &Path) -> RunState {
    let interrupted = dir.join(report::fe::CHECKPOINT).exists();
    let ended_well = |summary: serde_json::Value| {
        ENDED_UNFINISHED
            .iter()
            .all(|(key, _)| summary.get(key).is_none_or(|v| v.is_null()))
    };
    let summary = report::compare::fe_summary(dir).ok();
    match (holds_case(case, dir, summary.as_ref()), interrupted) {
        (false, _) => RunState::Other,
        (true, true) => RunState::Interrupted,
        (true, false) if summary.is_some_and(ended_well) => RunState::Finished,
        (true, false) => RunState::Other,
    }
}

/// A run summary's keys that say it did not finish (with how the verdict words it): a message
/// there, or null.
const ENDED_UNFINISHED: [(&str, &str); 2] =
    [("diverged", "diverged"), ("interrupted", "was interrupted")];

/// The folder's case.toml is `case` (as TOML values: comments and `--set` headers aside), and
/// its `summary`, if any, was meshed with the case's tooth layout: a run from before the
/// default layout changed (2026-12-06) has the same case file but a graded mesh.
fn holds_case(case: &Case, dir: &Path, summary: Option<&serde_json::Value>) -> bool {
    let layout_matches = summary.is_none_or(|summary| {
        report::compare::summary_tooth_layout(summary, dir)
            .is_ok_and(|layout| layout == case.fe.tooth_layout)
    });
    layout_matches
        && std::fs::read_to_string(dir.join("case.toml")).is_ok_and(|text| case.is_same_case(&text))
}

/// A run folder's verdict as a study takes it, whichever executor ran the run or found it
/// finished: `Ok` for a finished run of `case` whose checks against the LTCA passed, the reason
/// for one that failed them, diverged or was interrupted; None where the folder holds no
/// summary of this case to judge (the run stopped before it wrote one).
pub fn folder_verdict(case: &Case, dir: &Path) -> Option<std::result::Result<(), String>> {
    let summary = report::compare::fe_summary(dir)
        .ok()
        .filter(|summary| holds_case(case, dir, Some(summary)))?;
    let shown = dir.display();
    for (key, what) in ENDED_UNFINISHED {
        if let Some(message) = summary.get(key).and_then(|m| m.as_str()) {
            return Some(Err(format!("{shown}: the run {what}: {message}")));
        }
    }
    if dir.join(report::fe::CHECKPOINT).exists() {
        return Some(Err(format!(
            "{shown}: the run was interrupted (its checkpoint is kept)"
        )));
    }
    let failed: Vec<String> = summary
        .get("self_checks")
        .and_then(|c| c.as_array())
        .into_iter()
        .flatten()
        .filter(|c| c["passed"] == false && c["warning_only"] == false)
        .map(|c| c["quantity"].as_str().unwrap_or("?").to_string())
        .collect();
    if !failed.is_empty() {
        return Some(Err(format!(
            "{shown}: {} of the run's checks against the LTCA on its own mesh failed ({})",
            failed.len(),
            failed.join("; ")
        )));
    }
    Some(Ok(()))
}

/// `--checkpoint-every-s`, as bits of an f64 (600 s until set).
static CHECKPOINT_EVERY: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

pub fn set_checkpoint_every(seconds: f64) {
    CHECKPOINT_EVERY.store(seconds.to_bits(), std::sync::atomic::Ordering::Relaxed);
}

fn checkpoint_every() -> f64 {
    match f64::from_bits(CHECKPOINT_EVERY.load(std::sync::atomic::Ordering::Relaxed)) {
        s if s > 0.0 => s,
        _ => 600.0,
    }
}

pub fn progress_bar(template: &str) -> ProgressBar {
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
    bar
}

/// A bar for a study's staged progress (stage name, done, total).
pub fn staged_bar() -> ProgressBar {
    progress_bar("{msg} [{bar:40}] {pos}/{len}")
}

/// Drives `bar` from a study's progress callback.
pub fn stage(bar: &ProgressBar) -> impl Fn(&str, usize, usize) + Sync + '_ {
    move |name, done, total| {
        bar.set_message(name.to_string());
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }
}
