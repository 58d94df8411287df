//! Cost of building and checking the pair, and of sampling the modified outline that the FE mesh
//! starts from.

use criterion::{criterion_group, criterion_main, Criterion};
use geardyn::geometry::{GearPair, OutlineResolution};
use geardyn::samples;
use std::hint::black_box;

fn geometry(c: &mut Criterion) {
    let case = samples::paper36_case();
    c.bench_function("pair_new_paper36", |b| {
        b.iter(|| GearPair::new(black_box(&case.pair_spec)).unwrap())
    });
    let modification = case.relief_variant("tip20-root10").unwrap().modifications[0];
    let gear = &case.pair.gears[0];
    c.bench_function("gear_outline_paper36_36_teeth", |b| {
        b.iter(|| gear.gear_outline(black_box(&modification), OutlineResolution::default()))
    });
}

criterion_group!(benches, geometry);
criterion_main!(benches);
