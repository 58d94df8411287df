//! The memory estimates of the resource check held against the heap: a counting allocator
//! records the peak of live bytes while the model is built.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use geardyn::fe::assembly::{assembly_memory, stiffness_triplets, AssembledStiffness};
use geardyn::fe::elasticity_matrix;
use geardyn::geometry::FlankModification;
use geardyn::mesh::{mesh_gear, mesh_size, MeshSpec};
use geardyn::samples;

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
        PEAK.fetch_max(live, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            let live = LIVE.fetch_add(new_size - layout.size(), Ordering::SeqCst)
                + (new_size - layout.size());
            PEAK.fetch_max(live, Ordering::SeqCst);
        } else {
            LIVE.fetch_sub(layout.size() - new_size, Ordering::SeqCst);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// One measurement at a time: the counters are the process's, and the tests run in threads.
static MEASURING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Peak heap growth while `f` runs [bytes]; take [`MEASURING`] around it.
fn peak_of<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    let out = f();
    (out, (PEAK.load(Ordering::SeqCst) - before) as f64)
}

/// An LTCA body's two checked allocations against the heap on four meshes, from a coarse one
/// to fine = coarse: the mesh, triplets and K counted before meshing ([`assembly_memory`])
/// against the peak of meshing, computing the triplets and assembling K; the factor and its
/// workspace from the symbolic analysis ([`AssembledStiffness::factorization_memory`]) against
/// the peak of the numeric factorization.
///
/// The factor's estimate is the sizes of its two allocations, L's values and the workspace:
/// within 2 %. The count before meshing leaves out the symbolic analysis and faer's small work
/// arrays, so it is a lower bound of the assembly's peak: at least 90 % of it (97 % measured
/// on every mesh here). The first mesh is built twice: the first time also allocates the matrix
/// products' per-thread packing buffers (64 MiB, once per process), which are not the body's.
/// The factorizations run on this thread (faer's workspace depends on the thread count; the
/// estimate asks faer for it at the count in use, so this holds on any).
#[test]
fn ltca_body_memory_estimates_against_the_heap() {
    let _alone = MEASURING.lock().unwrap();
    let case = samples::paper36_case();
    let gear = &case.pair.gears[0];
    let none = FlankModification::none();
    let material = case.ltca_material();
    let d = elasticity_matrix(
        material.youngs_modulus,
        material.poisson_ratio,
        material.plane,
    );
    let teeth = geardyn::ltca::engaging_teeth(&case.pair)[0].clone();
    faer::set_global_parallelism(faer::Par::Seq);
    let mut rows = Vec::new();
    for (i, (fine_size, coarse_size)) in [
        (0.4e-3, 1.5e-3),
        (0.4e-3, 1.5e-3),
        (0.2e-3, 1.5e-3),
        (0.1e-3, 1.0e-3),
        (0.4e-3, 0.4e-3),
    ]
    .into_iter()
    .enumerate()
    {
        let spec = MeshSpec {
            fine_size,
            coarse_size,
            fine_teeth: teeth.clone(),
            layout: geardyn::mesh::ToothLayout::Graded,
        };
        let counted = assembly_memory(mesh_size(gear, &none, &spec)).total();
        let (assembled, assembly_peak) = peak_of(|| {
            let mesh = mesh_gear(gear, &none, &spec);
            let triplets =
                stiffness_triplets(&mesh.nodes, &mesh.elements, &d, gear.spec.face_width);
            let fixed: Vec<usize> = mesh
                .bore_nodes
                .iter()
                .flat_map(|&i| [2 * i, 2 * i + 1])
                .collect();
            (
                mesh.nodes.len(),
                AssembledStiffness::new(2 * mesh.nodes.len(), triplets, &fixed).unwrap(),
            )
        });
        let factor_estimate = assembled.1.factorization_memory().total();
        let (_factor, factor_peak) = peak_of(|| assembled.1.factorize().unwrap());
        eprintln!(
            "{} / {} mm: assembly {:.1} / {:.1} MB = {:.3}, factor {:.1} / {:.1} MB = {:.3}",
            fine_size * 1e3,
            coarse_size * 1e3,
            counted / 1e6,
            assembly_peak / 1e6,
            counted / assembly_peak,
            factor_estimate / 1e6,
            factor_peak / 1e6,
            factor_estimate / factor_peak
        );
        if i > 0 {
            rows.push((counted / assembly_peak, factor_estimate / factor_peak));
        }
    }
    assert!(
        rows.iter()
            .all(|&(assembly, factor)| (0.9..=1.0).contains(&assembly)
                && (0.98..1.02).contains(&factor)),
        "estimate / heap peak (assembly, factor): {rows:?}"
    );
}

/// The explicit run's estimate (history reserved for every sample, the integrator's arrays)
/// against the heap peak of the run, on the coarse pair: once with a sample every step, where
/// the history is most of it, once with one every 20 µs, where the state is. Within −10 % /
/// +5 %: the history's size is exact, the integrator's and the stable-step check's arrays are
/// counted per node; the contact search's small work arrays are left out (−1 % and −4 %
/// measured).
#[test]
fn explicit_run_memory_estimate_against_the_heap() {
    let _alone = MEASURING.lock().unwrap();
    use geardyn::case::{Case, Override};
    use geardyn::explicit::scene::{run, run_memory};
    let case = Case::load_with(
        None,
        &[
            Override::set("mesh.fine_element_mm", 1.5),
            Override::set("mesh.coarse_element_mm", 3.0),
            Override::set("fe.explicit_fine_element_mm", 1.5),
        ],
    )
    .unwrap();
    let mut scene = case.scene("low-unmodified").unwrap().clone();
    scene.driver_speed = 600.0 * std::f64::consts::TAU / 60.0;
    let prepared = geardyn::study::fe::prepare(&case, &scene).unwrap();
    let duration = 4000.0 * prepared.dt;
    let mut ratios = Vec::new();
    for interval in [prepared.dt, 20e-6] {
        let estimate = run_memory(&prepared, duration, interval);
        let (outcome, peak) =
            peak_of(|| run(&prepared, duration, interval, None, None, &mut |_| {}).unwrap());
        assert!(outcome.diverged.is_none());
        eprintln!(
            "output every {interval:.2e} s: estimate {} against {:.2} MB",
            estimate.describe(),
            peak / 1e6
        );
        ratios.push(estimate.total() / peak);
    }
    assert!(
        ratios.iter().all(|r| (0.9..1.05).contains(r)),
        "estimate / heap peak: {ratios:?}"
    );
}
