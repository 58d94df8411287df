//! Cost of the explicit kernel: corotational internal forces of one gear body at the default
//! mesh (one core), reported per element per step.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use geardyn::explicit::body::{ExplicitBody, ExplicitMaterial};
use geardyn::fe::PlaneState;
use geardyn::ltca::engaging_teeth;
use geardyn::mesh::mesh_gear;
use geardyn::samples;
use std::hint::black_box;

fn explicit(c: &mut Criterion) {
    let case = samples::paper36_case();
    let gear = &case.pair.gears[0];
    let mods = case.relief_variant("none").unwrap().modifications;
    let mesh = mesh_gear(
        gear,
        &mods[0],
        &case.mesh_spec(engaging_teeth(&case.pair)[0].clone()),
    );
    let material = ExplicitMaterial {
        youngs_modulus: case.material.youngs_modulus,
        poisson_ratio: case.material.poisson_ratio,
        density: case.material.density,
        plane: PlaneState::Strain,
        thickness: gear.spec.face_width,
    };
    let body = ExplicitBody::with_symmetry(
        &mesh.nodes,
        &mesh.elements,
        material,
        Some(gear.teeth() as usize),
    )
    .unwrap();
    eprintln!(
        "prototypes {} for {} elements, {} batches",
        body.prototypes.len(),
        mesh.elements.len(),
        body.batch_count()
    );
    let (s, co) = 0.3_f64.sin_cos();
    let x: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|p| [co * p.x - s * p.y + 1e-7, s * p.x + co * p.y])
        .collect();
    let v = vec![1e-3; x.len()];
    let mut force = vec![0.0; x.len()];
    let mut group = c.benchmark_group("explicit_paper36_default_mesh");
    group.throughput(Throughput::Elements(mesh.elements.len() as u64));
    group.bench_function("internal_forces_one_gear", |b| {
        b.iter(|| {
            force.iter_mut().for_each(|f| *f = 0.0);
            body.internal_forces(black_box(&x), &v, 0.0, &mut force)
        })
    });
    group.bench_function("internal_and_damping_forces_one_gear", |b| {
        b.iter(|| {
            force.iter_mut().for_each(|f| *f = 0.0);
            body.internal_forces(black_box(&x), &v, 1e-8, &mut force)
        })
    });
    group.finish();
    eprintln!(
        "elements {}, paper L/c {:.4e} s, element eigenvalue bound {:.4e} s",
        mesh.elements.len(),
        body.paper_critical_step(),
        body.element_eigen_critical_step()
    );
}

/// One central-difference step of the meshing pair at the default explicit mesh, for the scenes
/// low-unmodified (1 ms: three teeth per gear fine) and high-unmodified (its full 0.03 s: every
/// tooth fine): two per-gear parallel phases (rayon), contact search and forces, hubs.
fn pair_step(c: &mut Criterion) {
    use geardyn::explicit::pair::PairIntegrator;
    use geardyn::explicit::scene::{prepare, FeSettings};
    let case = samples::paper36_case();
    let mut group = c.benchmark_group("explicit_pair_paper36_default_mesh");
    group.sample_size(10);
    for (name, id, duration) in [
        ("low-unmodified", "step", Some(1e-3)),
        ("high-unmodified", "step_high_scene", None),
    ] {
        let mut scene = case.scene(name).unwrap().clone();
        if let Some(duration) = duration {
            scene.duration = duration;
        }
        let prepared = prepare(&case, &scene, &FeSettings::from_case(&case)).unwrap();
        let mut integrator = PairIntegrator::new(
            &prepared.model,
            prepared.drive,
            prepared.dt,
            prepared.beta_k,
        );
        let mut state = prepared.model.initial_state(0.0);
        integrator.initialize(&mut state);
        let elements = prepared.model.elements();
        eprintln!("pair {name}: {elements} elements, dt {:.3e} s", prepared.dt);
        group.throughput(Throughput::Elements(elements as u64));
        group.bench_function(id, |b| {
            b.iter(|| integrator.step(black_box(&mut state)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, explicit, pair_step);
criterion_main!(benches);
