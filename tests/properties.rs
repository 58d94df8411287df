//! Case parsing and geometry over generated cases (the sample `cargo test` can afford; `geardyn
//! validate properties` runs 100 000): every case is valid with finite outputs or rejected with
//! a message naming a parameter, none panics — and enough of the plausible ones are valid that
//! the check cannot pass by rejecting everything.

use geardyn::study::{no_progress, properties};

#[test]
fn generated_cases_are_valid_or_rejected_by_name_never_a_panic() {
    let report = properties::run(3000, 7, &no_progress);
    assert!(report.passed(), "{:#?}", report.failures);
    assert_eq!(report.valid + report.rejected, report.cases);
    // About 84 % of the cases with only plausible values are valid gears (the rest are
    // impossible combinations: undercut, interference, contact ratio out of [1, 2)); 50 % is
    // the floor, and a quarter of all cases.
    assert!(
        report.plausible_valid_share > 0.5,
        "{}",
        report.plausible_valid_share
    );
    assert!(
        report.valid as f64 > 0.25 * report.cases as f64,
        "{}",
        report.valid
    );
    assert!(
        report.rejected as f64 > 0.25 * report.cases as f64,
        "{}",
        report.rejected
    );
}

/// A sample is made from (seed, index) alone, so a failure is re-made from its index.
#[test]
fn a_sample_depends_on_its_seed_and_index_only() {
    let show = |v: Vec<(geardyn::case::Override, properties::Change)>| {
        v.iter()
            .map(|(o, c)| format!("{o} {c:?}"))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        show(properties::sample(1, 42)),
        show(properties::sample(1, 42))
    );
    assert_ne!(
        show(properties::sample(1, 42)),
        show(properties::sample(2, 42))
    );
}
