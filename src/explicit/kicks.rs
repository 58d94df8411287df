//! The central-difference updates of a gear's DOFs, one pass over arrays each, on the CPU's
//! widest vector unit.
//!
//! A step of the explicit pair (velocity Verlet form of the central difference, Belytschko et
//! al., *Nonlinear Finite Elements*, §6.2.1) is, per DOF,
//! ```text
//! v ← v + ½Δt a;  x ← x + Δt v                       (drift)
//! f = f_int + f_damp + f_contact                    (force phase)
//! a = f/m − α v;  v ← v + ½Δt a;  f ← 0              (kick)
//! ```
//! The passes are bound by the memory traffic of 13 000 DOFs a gear (five and six arrays
//! streamed), not by their arithmetic; built for the baseline x86-64 they run two lanes
//! (SSE2). Here the same loop bodies are compiled again for AVX2 and AVX-512 and chosen by
//! [`Kernel::best`], the element kernel's choice. Rust never fuses a multiply and an add into
//! one rounding unless asked, so every variant gives the same bits.

use std::ops::Range;

use crate::explicit::body::Kernel;

/// v ← v + ½Δt a;  x ← x + Δt v, over three arrays of one length.
pub fn drift(dt: f64, x: &mut [f64], v: &mut [f64], a: &[f64]) {
    assert!(x.len() == v.len() && v.len() == a.len());
    match Kernel::best() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `best` returns a kernel this CPU runs (AVX-512 F and DQ, AVX2, FMA).
        Kernel::Avx512 => unsafe { on_avx512(|| drift_body(dt, x, v, a)) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2 and FMA.
        Kernel::Avx2 => unsafe { on_avx2(|| drift_body(dt, x, v, a)) },
        _ => drift_body(dt, x, v, a),
    }
}

/// The closing kick over the DOFs of `runs` (ranges of indices into the arrays, each in
/// bounds): a = f w − α v where w = 1/m > 0 (a = 0 on a DOF held by its hub, w = 0),
/// v ← v + `half` · a, f ← 0 for the next step's sums. Returns the mass damping's power
/// Σ α v²/m over them (v before the kick), summed run by run in their order.
pub fn kick(
    alpha: f64,
    half: f64,
    runs: &[Range<usize>],
    w: &[f64],
    a: &mut [f64],
    v: &mut [f64],
    f: &mut [f64],
) -> f64 {
    assert!(w.len() == a.len() && a.len() == v.len() && v.len() == f.len());
    match Kernel::best() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `best` returns a kernel this CPU runs (AVX-512 F and DQ, AVX2, FMA).
        Kernel::Avx512 => unsafe { on_avx512(|| kick_runs(alpha, half, runs, w, a, v, f)) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2 and FMA.
        Kernel::Avx2 => unsafe { on_avx2(|| kick_runs(alpha, half, runs, w, a, v, f)) },
        _ => kick_runs(alpha, half, runs, w, a, v, f),
    }
}

/// [`kick`] of one DOF, for DOFs that are not contiguous (the flank and bore DOFs a step
/// kicks after its serial middle). The same arithmetic as the runs'.
#[inline(always)]
pub fn kick_one(alpha: f64, half: f64, w: f64, a: &mut f64, v: &mut f64, f: &mut f64) -> f64 {
    let mut power = 0.0;
    if alpha > 0.0 {
        if w > 0.0 {
            *a = *f * w - alpha * *v;
            power = alpha * *v * *v / w;
        } else {
            *a = 0.0;
        }
    } else {
        *a = *f * w;
    }
    *v += half * *a;
    *f = 0.0;
    power
}

#[inline(always)]
fn drift_body(dt: f64, x: &mut [f64], v: &mut [f64], a: &[f64]) {
    for ((x, v), a) in x.iter_mut().zip(v.iter_mut()).zip(a) {
        *v += 0.5 * dt * a;
        *x += dt * *v;
    }
}

#[inline(always)]
fn kick_runs(
    alpha: f64,
    half: f64,
    runs: &[Range<usize>],
    w: &[f64],
    a: &mut [f64],
    v: &mut [f64],
    f: &mut [f64],
) -> f64 {
    let mut power = 0.0;
    for r in runs {
        let (w, a, v, f) = (
            &w[r.clone()],
            &mut a[r.clone()],
            &mut v[r.clone()],
            &mut f[r.clone()],
        );
        if alpha > 0.0 {
            for (((a, v), f), w) in a.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(w) {
                power += kick_one(alpha, half, *w, a, v, f);
            }
        } else {
            // Without mass damping the branch-free form, which the compiler vectorizes.
            for (((a, v), f), w) in a.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(w) {
                *a = *f * w;
                *v += half * *a;
                *f = 0.0;
            }
        }
    }
    power
}

/// Runs `body` in a function built for AVX-512 (F and DQ), AVX2 and FMA: the body, inlined,
/// is compiled for those units. Safety: the CPU must have them.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
unsafe fn on_avx512<R>(body: impl FnOnce() -> R) -> R {
    body()
}

/// [`on_avx512`] for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn on_avx2<R>(body: impl FnOnce() -> R) -> R {
    body()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Arrays with every case of a DOF: free and held (w = 0), of both signs.
    fn arrays(n: usize) -> [Vec<f64>; 4] {
        let value = |i: usize, k: f64| ((i as f64 + 1.0) * k).sin() * 1e3;
        let w = (0..n)
            .map(|i| {
                if i % 7 == 3 {
                    0.0
                } else {
                    1.0 + value(i, 0.3).abs()
                }
            })
            .collect();
        [
            w,
            (0..n).map(|i| value(i, 1.1)).collect(),
            (0..n).map(|i| value(i, 2.3)).collect(),
            (0..n).map(|i| value(i, 0.7)).collect(),
        ]
    }

    /// The three-phase step's closing kick before 2026-12-06 (`PairIntegrator::accelerate`),
    /// verbatim but for the bore placement: the reference every variant must give bit for bit.
    fn old_kick(
        alpha: f64,
        half: f64,
        w: &[f64],
        a: &mut [f64],
        v: &mut [f64],
        f: &mut [f64],
    ) -> f64 {
        let mut power = 0.0;
        if alpha > 0.0 {
            for (((a, v), f), w) in a.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(w) {
                if *w > 0.0 {
                    *a = *f * w - alpha * *v;
                    power += alpha * *v * *v / w;
                } else {
                    *a = 0.0;
                }
                *v += half * *a;
                *f = 0.0;
            }
        } else {
            for (((a, v), f), w) in a.iter_mut().zip(v.iter_mut()).zip(f.iter_mut()).zip(w) {
                *a = *f * w;
                *v += half * *a;
                *f = 0.0;
            }
        }
        power
    }

    /// Every variant this CPU runs (portable, AVX2, AVX-512, and the dispatch) gives the bits of
    /// the old kick over runs with gaps (the gaps untouched), and of the old drift, with and
    /// without mass damping, over lengths that leave vector remainders.
    #[test]
    fn every_variant_gives_the_old_passes_bits() {
        type KickFn =
            fn(f64, f64, &[Range<usize>], &[f64], &mut [f64], &mut [f64], &mut [f64]) -> f64;
        type DriftFn = fn(f64, &mut [f64], &mut [f64], &[f64]);
        let mut variants: Vec<(&str, KickFn, DriftFn)> = vec![
            (
                "portable",
                |al, h, r, w, a, v, f| kick_runs(al, h, r, w, a, v, f),
                |dt, x, v, a| drift_body(dt, x, v, a),
            ),
            ("dispatched", kick, drift),
        ];
        #[cfg(target_arch = "x86_64")]
        {
            if Kernel::Avx2.available() {
                // SAFETY: the CPU has AVX2 and FMA (checked above).
                variants.push((
                    "avx2",
                    |al, h, r, w, a, v, f| unsafe { on_avx2(|| kick_runs(al, h, r, w, a, v, f)) },
                    |dt, x, v, a| unsafe { on_avx2(|| drift_body(dt, x, v, a)) },
                ));
            }
            if Kernel::Avx512.available() {
                // SAFETY: the CPU has AVX-512 F and DQ, AVX2 and FMA (checked above).
                variants.push((
                    "avx512",
                    |al, h, r, w, a, v, f| unsafe { on_avx512(|| kick_runs(al, h, r, w, a, v, f)) },
                    |dt, x, v, a| unsafe { on_avx512(|| drift_body(dt, x, v, a)) },
                ));
            }
        }
        for (name, kick_variant, drift_variant) in variants {
            for n in [0, 1, 7, 8, 17, 1001] {
                let gapped = [(0, n / 3), (n / 3 + 1, n / 2), (n / 2 + 3, n)].map(|(a, b)| {
                    let start = a.min(n);
                    start..b.max(start)
                });
                // One run over the whole array: the old kick's own extent.
                #[allow(clippy::single_range_in_vec_init)]
                let whole = [0..n];
                for (runs, alpha) in [
                    (&gapped[..], 0.0),
                    (&gapped[..], 37.5),
                    (&whole[..], 0.0),
                    (&whole[..], 37.5),
                ] {
                    let [w, a0, v0, f0] = arrays(n);
                    let (mut a, mut v, mut f) = (a0.clone(), v0.clone(), f0.clone());
                    let power = kick_variant(alpha, 0.5e-8, runs, &w, &mut a, &mut v, &mut f);
                    let (mut a1, mut v1, mut f1) = (a0.clone(), v0.clone(), f0.clone());
                    let mut power1 = 0.0;
                    for r in runs {
                        let r = r.clone();
                        power1 += old_kick(
                            alpha,
                            0.5e-8,
                            &w[r.clone()],
                            &mut a1[r.clone()],
                            &mut v1[r.clone()],
                            &mut f1[r],
                        );
                    }
                    let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&a), bits(&a1), "{name}: a, n {n}, alpha {alpha}");
                    assert_eq!(bits(&v), bits(&v1), "{name}: v, n {n}, alpha {alpha}");
                    assert_eq!(bits(&f), bits(&f1), "{name}: f, n {n}, alpha {alpha}");
                    // The power's sum over several runs is one running sum; over the whole
                    // array it is the old one's.
                    if runs.len() == 1 {
                        assert_eq!(power.to_bits(), power1.to_bits(), "{name}: power");
                    }
                    // The one-DOF form of the held DOFs, too.
                    let (mut a2, mut v2, mut f2) = (a0.clone(), v0.clone(), f0.clone());
                    for d in runs.iter().flat_map(|r| r.clone()) {
                        kick_one(alpha, 0.5e-8, w[d], &mut a2[d], &mut v2[d], &mut f2[d]);
                    }
                    assert_eq!(
                        (bits(&a2), bits(&v2), bits(&f2)),
                        (bits(&a1), bits(&v1), bits(&f1)),
                        "{name}: kick_one, n {n}"
                    );
                }
                let [x0, a0, v0, _] = arrays(n);
                let (mut x, mut v) = (x0.clone(), v0.clone());
                drift_variant(1e-8, &mut x, &mut v, &a0);
                for d in 0..n {
                    // The old drift: v += ½Δt a; x += Δt v.
                    let vd = v0[d] + 0.5 * 1e-8 * a0[d];
                    assert_eq!(v[d].to_bits(), vd.to_bits(), "{name}: drift v");
                    assert_eq!(
                        x[d].to_bits(),
                        (x0[d] + 1e-8 * vd).to_bits(),
                        "{name}: drift x"
                    );
                }
            }
        }
    }
}
