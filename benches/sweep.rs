//! Lumped-model cost: the paper's pair on a stiffness table with a double-contact step, 1-DOF with
//! backlash, 600 driver speeds from 100 to 12 000 rpm to periodic steady state (up- and
//! down-sweep), and the 600-point Floquet map; and the default case as `geardyn sweep` runs it
//! (the LTCA's load-dependent force law, elastic bodies): its tables and its 600-speed sweep.

use criterion::{criterion_group, criterion_main, Criterion};
use geardyn::case::{Case, Override};
use geardyn::study::lumped::setup;
use geardyn::sweep::{floquet_map, sweep};
use std::hint::black_box;

fn lumped(c: &mut Criterion) {
    // The embedded case's lumped model on the potential-energy stiffness (torque drive,
    // ζ = 0.05), with 50 µm of backlash so the separating branch is exercised.
    let case = Case::load_with(None, &[Override::set("lumped.stiffness", "pe")]).unwrap();
    let mut model = setup(&case).unwrap().model;
    model.backlash = Some(50e-6);
    let rpms: Vec<f64> = (0..600)
        .map(|i| 100.0 + (12000.0 - 100.0) * i as f64 / 599.0)
        .collect();
    let mut group = c.benchmark_group("lumped_paper36");
    group.sample_size(10);
    group.bench_function("sweep_600_points_up_and_down", |b| {
        b.iter(|| sweep(black_box(&model), &rpms))
    });
    group.bench_function("floquet_map_600_points", |b| {
        b.iter(|| floquet_map(black_box(&model), &rpms))
    });
    group.finish();
}

fn default_case(c: &mut Criterion) {
    let case = Case::load_with(None, &[]).unwrap();
    let model = setup(&case).unwrap().model;
    let rpms: Vec<f64> = (0..600)
        .map(|i| 100.0 + (12000.0 - 100.0) * i as f64 / 599.0)
        .collect();
    let mut group = c.benchmark_group("lumped_paper36_default_case");
    group.sample_size(10);
    group.bench_function("force_law_tables_and_checks", |b| {
        b.iter(|| setup(black_box(&case)).unwrap())
    });
    group.bench_function("sweep_600_points_up_and_down", |b| {
        b.iter(|| sweep(black_box(&model), &rpms))
    });
    group.finish();
}

criterion_group!(benches, lumped, default_case);
criterion_main!(benches);
