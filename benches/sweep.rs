//! Lumped-model cost: the paper's pair on a stiffness table with a double-contact step, 1-DOF with
//! backlash, 600 driver speeds from 100 to 12 000 rpm to periodic steady state (up- and
//! down-sweep), and the 600-point Floquet map.

use criterion::{criterion_group, criterion_main, Criterion};
use geardyn::fe::PlaneState;
use geardyn::lumped::{MeshModel, PeriodicTable};
use geardyn::samples;
use geardyn::stiffness::potential_energy::potential_energy_table;
use geardyn::sweep::{floquet_map, sweep};
use std::hint::black_box;

fn lumped(c: &mut Criterion) {
    let pair = samples::paper36_pair();
    let table = potential_energy_table(&pair, 64, 206e9, 0.3, PlaneState::Strain);
    let period = pair.gears[0].angular_pitch();
    let mut model = MeshModel {
        effective_mass: 0.57,
        stiffness: PeriodicTable {
            period,
            values: table.stiffness,
        },
        unloaded_te: PeriodicTable::constant(period, 0.0),
        damping: 0.0,
        force: 143.6 / pair.gears[1].base_radius,
        backlash: Some(50e-6),
        bearings: None,
    };
    model.damping = model.damping_from_ratio(0.05);
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

criterion_group!(benches, lumped);
criterion_main!(benches);
