//! Cost of the explicit kernel: corotational internal forces of one gear body (one core),
//! reported per element per step; and of the meshing pair's whole step.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use geardyn::explicit::body::ExplicitBody;
use geardyn::ltca::engaging_teeth;
use geardyn::mesh::mesh_gear;
use geardyn::samples;
use std::hint::black_box;

/// A mesh's nodes turned by 0.3 rad and shifted by 0.1 µm, a uniform velocity, a zero force.
fn turned_state(mesh: &geardyn::mesh::GearMesh) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (s, co) = 0.3_f64.sin_cos();
    let x: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|p| [co * p.x - s * p.y + 1e-7, s * p.x + co * p.y])
        .collect();
    let n = x.len();
    (x, vec![1e-3; n], vec![0.0; n])
}

fn explicit(c: &mut Criterion) {
    let case = samples::paper36_case();
    let gear = &case.pair.gears[0];
    let mods = case.relief_variant("none").unwrap().modifications;
    // The LTCA's mesh (0.2 mm flanks on the three engaging teeth: few congruent copies, so the
    // element matrices stream from memory) and the 3000 rpm scenes' body (the explicit sizes,
    // every tooth fine: each matrix serves 36 elements).
    let meshes = [
        (
            "ltca_mesh",
            mesh_gear(
                gear,
                &mods[0],
                &case.mesh_spec(engaging_teeth(&case.pair)[0].clone()),
            ),
        ),
        (
            "high_scene_body",
            samples::explicit_gear_mesh(&case, 0, (0..gear.teeth() as usize).collect()),
        ),
    ];
    let material = samples::paper36_explicit_material();
    let mut group = c.benchmark_group("explicit_paper36_kernel");
    for (name, mesh) in &meshes {
        let body = ExplicitBody::with_symmetry(
            &mesh.nodes,
            &mesh.elements,
            material,
            Some(gear.teeth() as usize),
        )
        .unwrap();
        eprintln!(
            "{name}: {} elements, {} prototypes, {} batches; paper L/c {:.4e} s, element \
             eigenvalue bound {:.4e} s",
            mesh.elements.len(),
            body.prototypes.len(),
            body.batch_count(),
            body.paper_critical_step(),
            body.element_eigen_critical_step()
        );
        let (x, v, mut force) = turned_state(mesh);
        group.throughput(Throughput::Elements(mesh.elements.len() as u64));
        for (label, beta_k) in [("undamped", 0.0), ("damped", 1e-8)] {
            group.bench_function(format!("{name}/{label}"), |b| {
                b.iter(|| {
                    force.iter_mut().for_each(|f| *f = 0.0);
                    body.internal_forces(black_box(&x), &v, beta_k, &mut force)
                })
            });
        }
    }
    group.finish();
}

/// One central-difference step of the meshing pair at the default explicit mesh, for the scenes
/// low-unmodified (1 ms, from rest: three teeth per gear fine) and high-unmodified (every tooth
/// fine), the latter with the teeth in mesh: its ramp shortened to 0.1 ms and the step measured
/// from 0.15 ms on, when 20–26 Gauss points are in contact. Two per-gear parallel phases
/// (rayon), contact search and forces, hubs.
fn pair_step(c: &mut Criterion) {
    use geardyn::explicit::pair::PairIntegrator;
    let case = samples::paper36_case();
    let mut group = c.benchmark_group("explicit_pair_paper36_default_mesh");
    group.sample_size(10);
    // (scene, bench id, duration, ramp, start of the measured steps) [s]
    for (name, id, duration, ramp, start) in [
        ("low-unmodified", "step", Some(1e-3), None, 0.0),
        (
            "high-unmodified",
            "step_high_scene_meshing",
            None,
            Some(1e-4),
            1.5e-4,
        ),
    ] {
        let mut scene = case.scene(name).unwrap().clone();
        if let Some(duration) = duration {
            scene.duration = duration;
        }
        if let Some(ramp) = ramp {
            scene.ramp_time = ramp;
        }
        let prepared = geardyn::study::fe::prepare(&case, &scene).unwrap();
        let mut integrator = PairIntegrator::new(
            &prepared.model,
            prepared.drive,
            prepared.dt,
            prepared.beta_k,
        );
        let mut state = prepared.model.initial_state(&prepared.drive);
        integrator.initialize(&mut state);
        while state.time < start {
            integrator.step(&mut state).unwrap();
        }
        let elements = prepared.model.elements();
        eprintln!(
            "pair {name}: {elements} elements, dt {:.3e} s, {} Gauss points in contact",
            prepared.dt, integrator.last_contact.active
        );
        group.throughput(Throughput::Elements(elements as u64));
        group.bench_function(id, |b| {
            b.iter(|| integrator.step(black_box(&mut state)).unwrap())
        });
    }
    group.finish();
}

/// What a reduced far block would save a step (issue 31): the 3000 rpm scene's window mesh of
/// the driver (six fine teeth, explicit sizes), its other thirty sectors' elements through the
/// element kernel (damped, one core) against the same block reduced by Craig–Bampton at an
/// 80 kHz cutoff ([`geardyn::explicit::reduced`]): its interface motion and accelerations with
/// the hub turned at a prescribed rate (the driver) and with a free hub (the driven gear); the
/// same prescribed step of the block the pair builds (`fe.far_body = "reduced"`: its modes to
/// [`geardyn::explicit::far::FAR_BLOCK_CUTOFF`] times the fine sectors' lowest); the whole
/// gear's and the six fine sectors' elements for scale.
fn reduced_block(c: &mut Criterion) {
    use geardyn::explicit::reduced::{Cutoff, FrameMotion, ReducedBlock};
    let case = samples::paper36_case();
    let gear = &case.pair.gears[0];
    let mesh = samples::explicit_gear_mesh(&case, 0, (0..6).collect());
    let material = samples::paper36_explicit_material();
    let whole = ExplicitBody::new(&mesh.nodes, &mesh.elements, material).unwrap();
    let in_block: Vec<bool> = mesh.element_fine.iter().map(|f| !f).collect();
    let (block_elements, fine_elements) =
        geardyn::explicit::reduced::split_elements(&mesh.elements, &in_block);
    let body_of = |elements: &[[usize; 8]]| {
        ExplicitBody::with_symmetry(&mesh.nodes, elements, material, Some(gear.teeth() as usize))
            .unwrap()
    };
    let elements = body_of(&block_elements);
    let fine = body_of(&fine_elements);
    let whole_symmetric = body_of(&mesh.elements);
    let block_at = |cutoff: Cutoff, rate_bound: f64| {
        let block = ReducedBlock::new(
            &mesh.nodes,
            &mesh.elements,
            &in_block,
            &mesh.bore_nodes,
            &whole.mass,
            &material,
            cutoff,
            rate_bound,
        )
        .unwrap();
        eprintln!(
            "reduced block at {cutoff:?}, Coriolis couplings among {} modes: {} of {} elements, {} interface nodes, {} internal nodes, {} modes, {} reduced DOFs",
            block.coriolis_modes(),
            block_elements.len(),
            mesh.elements.len(),
            block.interface.len(),
            block.internal.len(),
            block.mode_frequencies_hz.len(),
            block.dofs()
        );
        block
    };
    let block = block_at(Cutoff::Hz(80e3), f64::INFINITY);
    let pair_cutoff = Cutoff::BesideBlockTimes(geardyn::explicit::far::FAR_BLOCK_CUTOFF);
    let pair_block = block_at(pair_cutoff, f64::INFINITY);
    // The pair's bound at 3000 rpm (twice the speed, explicit::far::RATE_BOUND_FACTOR).
    let bounded_block = block_at(pair_cutoff, 2.0 * 314.16);
    let mut group = c.benchmark_group("reduced_block_paper36_window");
    let (x, v, mut force) = turned_state(&mesh);
    for (name, body) in [
        ("whole_gear_damped", &whole_symmetric),
        ("block_elements_damped", &elements),
        ("fine_elements_damped", &fine),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                force.iter_mut().for_each(|f| *f = 0.0);
                body.internal_forces(black_box(&x), &v, 1.3e-9, &mut force)
            })
        });
    }
    // A deformed, moving state of a block.
    let state_of = |block: &ReducedBlock| {
        let mut state = block.rest();
        state
            .eta
            .iter_mut()
            .enumerate()
            .for_each(|(k, z)| *z = 1e-9 * (k as f64).sin());
        state
            .rate
            .iter_mut()
            .enumerate()
            .for_each(|(k, z)| *z = 1e-4 * (k as f64).cos());
        state
    };
    let mut state = state_of(&block);
    let interface_force = vec![10.0; block.interface_dofs()];
    let mut scratch = block.scratch();
    let frame = FrameMotion {
        rate: 314.0,
        accel: 10.0,
    };
    for (name, block) in [
        ("reduced_prescribed", &block),
        ("reduced_prescribed_pair_cutoff", &pair_block),
        (
            "reduced_prescribed_pair_cutoff_coriolis_bound",
            &bounded_block,
        ),
    ] {
        let mut state = state_of(block);
        let mut scratch = block.scratch();
        group.bench_function(name, |b| {
            b.iter(|| {
                block.interface_motion(black_box(&state), &mut scratch);
                block.accelerate_prescribed(
                    &mut state,
                    frame,
                    1.3e-9,
                    &interface_force,
                    &mut scratch,
                )
            })
        });
    }
    group.bench_function("reduced_interface_motion_only", |b| {
        b.iter(|| block.interface_motion(black_box(&state), &mut scratch))
    });
    group.bench_function("reduced_free", |b| {
        b.iter(|| {
            block.interface_motion(black_box(&state), &mut scratch);
            block.accelerate_free(
                &mut state,
                3e-3,
                314.0,
                100.0,
                1.3e-9,
                &interface_force,
                &mut scratch,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, explicit, pair_step, reduced_block);
criterion_main!(benches);
