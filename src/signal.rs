//! Signal processing of time histories: windowed amplitude spectra (rustfft), the Daubechies-5
//! discrete wavelet transform (level-1 detail for impact detection, as in the seed paper) and
//! wavelet de-noising.
//!
//! # Amplitude spectrum
//! The mean is removed, a Hann window w applied, and |X_k|·2/Σw gives the amplitude of a sinusoid
//! at bin k in the signal's units (exact at bin centres; up to −1.4 dB between bins).
//!
//! # Peaks
//! A line is a local maximum of the amplitude spectrum (≥ its right neighbour, > its left one)
//! above 1e-9 of the largest line; the strongest come first.
//!
//! # db5 DWT (periodization)
//! With the 10-tap decomposition filters h (low-pass, Daubechies 1992, *Ten Lectures*, table 6.1)
//! and g[j] = (−1)^{j+1} h[9 − j] (high-pass):
//! ```text
//! a[i] = Σ_j h[j] x[(2i + 5 − j) mod N],   d[i] = Σ_j g[j] x[(2i + 5 − j) mod N],   i < N/2
//! ```
//! — PyWavelets' `dwt(x, 'db5', mode='periodization')`, checked against it in the tests (an odd
//! N is extended by repeating the last sample, as PyWavelets does). The transform is orthogonal,
//! so the inverse is its transpose.
//!
//! # Level-1 detail without wrap-around
//! For impacts the record is extended at each end by a half-sample symmetric reflection before
//! the level-1 transform ([`level1_detail`]): the periodized transform alone joins the record's
//! end to its start, and a force record that ends at full load and starts at zero shows that
//! step as a detail of 0.44 × the load.
//!
//! # De-noising
//! Soft thresholding of the detail coefficients of a multi-level db5 DWT at the universal
//! threshold σ√(2 ln N), σ = median|d₁|/0.6745 (Donoho & Johnstone 1994), then the inverse DWT.

use rustfft::{num_complex::Complex, FftPlanner};

/// db5 decomposition low-pass filter.
pub const DB5_LOW: [f64; 10] = [
    0.003_335_725_285_473_771_2,
    -0.012_580_751_999_081_999,
    -0.006_241_490_212_798_274,
    0.077_571_493_840_045_72,
    -0.032_244_869_584_638_375,
    -0.242_294_887_066_382_03,
    0.138_428_145_901_320_74,
    0.724_308_528_437_772_9,
    0.603_829_269_797_189_6,
    0.160_102_397_974_192_93,
];

/// db5 decomposition high-pass filter g[j] = (−1)^{j+1} h[9 − j].
pub fn db5_high() -> [f64; 10] {
    std::array::from_fn(|j| {
        let sign = if j % 2 == 0 { -1.0 } else { 1.0 };
        sign * DB5_LOW[9 - j]
    })
}

/// The smallest and the largest value (∞ and −∞ for none).
pub fn extremes(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// The largest of `values`; NaN if any is NaN, −∞ if there are none: for the checks a run
/// makes of its own answer, where a fold with `f64::max` would drop a NaN and pass.
pub fn largest(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(f64::NEG_INFINITY, |a, b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    })
}

/// Root mean square of `values` about their mean (0 for none).
pub fn rms_about_mean(values: &[f64]) -> f64 {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    (values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt()
}

/// max − min of `values` (−∞ for none).
pub fn peak_to_peak(values: &[f64]) -> f64 {
    let (lo, hi) = extremes(values);
    hi - lo
}

/// Index of the value nearest `target` (None for none).
pub fn nearest_index(values: &[f64], target: f64) -> Option<usize> {
    (0..values.len()).min_by(|&a, &b| {
        (values[a] - target)
            .abs()
            .total_cmp(&(values[b] - target).abs())
    })
}

/// One level of the periodized db5 DWT: (approximation, detail), each ⌈N/2⌉ long.
pub fn dwt_db5(x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut signal = x.to_vec();
    if signal.len() % 2 == 1 {
        signal.push(*x.last().expect("a non-empty signal"));
    }
    let n = signal.len();
    let high = db5_high();
    let half = n / 2;
    let mut approximation = vec![0.0; half];
    let mut detail = vec![0.0; half];
    for i in 0..half {
        let (mut a, mut d) = (0.0, 0.0);
        for j in 0..10 {
            let k = (2 * i + 5 + 10 * n - j) % n;
            a += DB5_LOW[j] * signal[k];
            d += high[j] * signal[k];
        }
        approximation[i] = a;
        detail[i] = d;
    }
    (approximation, detail)
}

/// Inverse of [`dwt_db5`] for an even length N = 2·len (the transpose of the orthogonal map).
pub fn idwt_db5(approximation: &[f64], detail: &[f64]) -> Vec<f64> {
    let n = 2 * approximation.len();
    let high = db5_high();
    let mut x = vec![0.0; n];
    for i in 0..approximation.len() {
        for j in 0..10 {
            let k = (2 * i + 5 + 10 * n - j) % n;
            x[k] += DB5_LOW[j] * approximation[i] + high[j] * detail[i];
        }
    }
    x
}

/// Samples of reflection added at each end of a record before its level-1 transform: more than
/// the filter's reach (a coefficient of sample k reads samples k − 5 … k + 5 of the extended
/// record), and even, so the coefficients keep their pairing with the samples.
pub const LEVEL1_PAD: usize = 10;

/// The level-1 db5 detail coefficients of `x`, each held over two samples so they can be
/// plotted against the signal: the paper's impact signature. Coefficient i weighs samples
/// 2i − 4 … 2i + 5 and most of all 2i + 3 (|g₂| = 0.72): it is shown at samples 2i + 3 and
/// 2i + 4, so an impact's detail stands where the impact is.
///
/// The record is extended at both ends by [`LEVEL1_PAD`] samples of half-sample symmetric
/// reflection (x₋₁ = x₀, x₋₂ = x₁, …; PyWavelets' `symmetric` mode) before the periodized
/// transform, so no coefficient reads across the wrap from the record's end to its start: a
/// record that ends at full load no longer shows the step end → start as a detail of
/// 0.44 × the load. A constant, linear or slowly varying record has details near zero up to
/// its ends (db5 has five vanishing moments; the reflection leaves a kink, whose detail is of
/// the order of the signal's change per sample).
pub fn level1_detail(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let reflect = |i: usize| x[i.min(n - 1)];
    let mut extended = Vec::with_capacity(n + 2 * LEVEL1_PAD);
    extended.extend((0..LEVEL1_PAD).rev().map(reflect));
    extended.extend_from_slice(x);
    extended.extend((0..LEVEL1_PAD).map(|i| reflect(n.saturating_sub(1 + i))));
    let (_, detail) = dwt_db5(&extended);
    (0..n).map(|k| detail[(k + LEVEL1_PAD - 3) / 2]).collect()
}

/// Largest |level-1 detail| of `x` over the samples `from..` (the statistics window), with
/// the whole record transformed so the window's start sees real neighbours.
pub fn level1_detail_max(x: &[f64], from: usize) -> f64 {
    level1_detail(x)
        .iter()
        .skip(from)
        .map(|d| d.abs())
        .fold(0.0, f64::max)
}

/// Wavelet de-noising: `levels` levels of db5 (fewer if the signal is short), soft threshold
/// at the universal threshold, inverse transform. Returns a signal of the input's length.
pub fn denoise(x: &[f64], levels: usize) -> Vec<f64> {
    if x.len() < 32 {
        return x.to_vec();
    }
    // Work on a length divisible by 2^levels (pad by repeating the last sample).
    let levels = levels.min((x.len() as f64 / 16.0).log2().floor().max(1.0) as usize);
    let block = 1usize << levels;
    let n = x.len().div_ceil(block) * block;
    let mut signal = x.to_vec();
    signal.resize(n, *x.last().expect("non-empty"));
    let mut details = Vec::with_capacity(levels);
    let mut approximation = signal;
    for _ in 0..levels {
        let (a, d) = dwt_db5(&approximation);
        details.push(d);
        approximation = a;
    }
    let mut finest: Vec<f64> = details[0].iter().map(|d| d.abs()).collect();
    finest.sort_by(f64::total_cmp);
    let sigma = finest[finest.len() / 2] / 0.6745;
    let threshold = sigma * (2.0 * (n as f64).ln()).sqrt();
    for d in &mut details {
        for c in d.iter_mut() {
            *c = c.signum() * (c.abs() - threshold).max(0.0);
        }
    }
    for d in details.iter().rev() {
        approximation = idwt_db5(&approximation, d);
    }
    approximation.truncate(x.len());
    approximation
}

/// Single-sided amplitude spectrum of a uniformly sampled signal (time step `dt`): mean removed,
/// Hann window, amplitudes in the signal's units. Returns (frequency [Hz], amplitude) for bins
/// 0 … N/2.
pub fn hann_amplitude_spectrum(x: &[f64], dt: f64) -> Vec<(f64, f64)> {
    let n = x.len();
    if n < 2 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let window: Vec<f64> = (0..n)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
        .collect();
    let sum: f64 = window.iter().sum();
    let mut buffer: Vec<Complex<f64>> = x
        .iter()
        .zip(&window)
        .map(|(v, w)| Complex::new((v - mean) * w, 0.0))
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    (0..=n / 2)
        .map(|k| {
            let scale = if k == 0 { 1.0 } else { 2.0 };
            (k as f64 / (n as f64 * dt), scale * buffer[k].norm() / sum)
        })
        .collect()
}

/// Single-sided amplitude spectrum of a record covering `periods` whole mesh periods:
/// amplitudes 2|X_k|/N at k = 1 … N/2, line k at k/periods mesh orders.
pub fn amplitude_spectrum(record: &[f64]) -> Vec<f64> {
    let n = record.len();
    let mut buffer: Vec<Complex<f64>> = record.iter().map(|x| Complex::new(*x, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    buffer[1..=n / 2]
        .iter()
        .map(|c| 2.0 * c.norm() / n as f64)
        .collect()
}

/// The samples in the longest whole number k ≥ 1 of periods 1/f, sampled every `dt`, that fit
/// in `len` samples, round(k/(f dt)), to within half a sample (a record cut to k periods to the
/// nearest sample keeps k); `None` where not one period fits (or f dt is not positive).
pub fn whole_period_samples(len: usize, dt: f64, f: f64) -> Option<usize> {
    let per_period = 1.0 / (f * dt);
    let periods = ((len as f64 + 0.5) / per_period).floor();
    match periods >= 1.0 && per_period.is_finite() {
        true => Some(((periods * per_period).round() as usize).min(len)).filter(|n| *n > 0),
        false => None,
    }
}

/// Amplitudes of the harmonics n·f, n = 1 … `count`, of a record sampled every `dt`, over the
/// longest whole number of periods 1/f from its end: |2/N Σ x_k e^{−i2πnf t_k}| (a DFT at the
/// exact harmonic frequencies, so they need not fall on FFT bins), the record's mean removed
/// first. A record shorter than one period gives zeros.
pub fn harmonic_amplitudes(x: &[f64], dt: f64, f: f64, count: usize) -> Vec<f64> {
    let Some(n) = whole_period_samples(x.len(), dt, f) else {
        return vec![0.0; count];
    };
    // The window holds whole periods only to the nearest sample: remove the mean, or a large
    // mean leaks into small harmonics.
    let tail = &x[x.len() - n..];
    let mean = tail.iter().sum::<f64>() / n as f64;
    let record: Vec<f64> = tail.iter().map(|v| v - mean).collect();
    (1..=count)
        .map(|h| {
            let w = std::f64::consts::TAU * h as f64 * f * dt;
            let (re, im) = record
                .iter()
                .enumerate()
                .fold((0.0, 0.0), |(re, im), (k, v)| {
                    let phase = w * k as f64;
                    (re + v * phase.cos(), im - v * phase.sin())
                });
            2.0 * (re * re + im * im).sqrt() / n as f64
        })
        .collect()
}

/// The `count` largest local maxima of an amplitude spectrum: (line index from 1, amplitude).
/// Lines below 1e-9 of the largest are rounding noise and are left out.
pub fn strongest_lines(spectrum: &[f64], count: usize) -> Vec<(usize, f64)> {
    let floor = 1e-9 * spectrum.iter().copied().fold(0.0, f64::max);
    let at = |i: isize| {
        if i < 0 {
            0.0
        } else {
            spectrum.get(i as usize).copied().unwrap_or(0.0)
        }
    };
    let mut lines: Vec<(usize, f64)> = (0..spectrum.len())
        .filter(|&i| {
            let a = spectrum[i];
            a > floor && a > at(i as isize - 1) && a >= at(i as isize + 1)
        })
        .map(|i| (i + 1, spectrum[i]))
        .collect();
    lines.sort_by(|a, b| b.1.total_cmp(&a.1));
    lines.truncate(count);
    lines
}

/// The strongest local maxima of a spectrum (bins 0 … N/2) above `min_hz`: (frequency,
/// amplitude), by [`strongest_lines`].
pub fn spectrum_peaks(spectrum: &[(f64, f64)], min_hz: f64, count: usize) -> Vec<(f64, f64)> {
    if spectrum.len() < 2 {
        return Vec::new();
    }
    let amplitudes: Vec<f64> = spectrum[1..].iter().map(|p| p.1).collect();
    strongest_lines(&amplitudes, amplitudes.len())
        .into_iter()
        .map(|(line, amplitude)| (spectrum[line].0, amplitude))
        .filter(|(frequency, _)| *frequency >= min_hz)
        .take(count)
        .collect()
}

/// The window's last three stretches of equal whole numbers of mesh periods (`len` samples every
/// `dt`, mesh frequency `mesh_hz`), contiguous and ending at the window's end, as sample ranges:
/// a periodic response has the same rms over each, whatever its phase, where thirds of a
/// fractional number of periods differ by up to a few tenths of a per cent (the part period's
/// share of the rms). Shorter than three mesh periods: plain thirds; shorter than three
/// samples: `None`.
pub fn whole_period_thirds(
    len: usize,
    dt: f64,
    mesh_hz: f64,
) -> Option<[std::ops::Range<usize>; 3]> {
    let third = whole_period_samples(len / 3, dt, mesh_hz).unwrap_or(len / 3);
    match third {
        0 => None,
        n => Some([len - 3 * n..len - 2 * n, len - 2 * n..len - n, len - n..len]),
    }
}

/// The rms about the mean over each of `window`'s [`whole_period_thirds`] (samples every `dt`,
/// mesh frequency `mesh_hz`), with the thirds; `None` where the window is too short to split.
pub fn thirds_rms(
    window: &[f64],
    dt: f64,
    mesh_hz: f64,
) -> Option<([f64; 3], [std::ops::Range<usize>; 3])> {
    let thirds = whole_period_thirds(window.len(), dt, mesh_hz)?;
    let rms = thirds.clone().map(|t| rms_about_mean(&window[t]));
    Some((rms, thirds))
}

/// Relative change of the rms between consecutive thirds of a window below which the response
/// counts as flat and its drift as the last change: the floor of what three thirds can tell
/// from a response's content away from the mesh harmonics (a body mode's residual ringing,
/// the hunting of unequal teeth) beating across them. Whole-period thirds of a steady periodic
/// response agree to within the one-sample rounding of their length (below 1e-6 at the FE's
/// steps, `study::fe_sweep`'s `whole_period_thirds_of_a_steady_response_agree`). Below the
/// floor a slow approach is not seen: with thirds of length T, a remainder up to about
/// FLAT_THIRDS·τ/T is hidden (at 6 ms thirds, 3 % for τ ≳ 60 ms; a 4.4 % approach with
/// τ = 0.1 s reads 0.27 %), and the drift jumps at the floor (changes of 0.29 % read 0.29 %,
/// of 0.31 % slowing by q = 0.97 read about 9 %).
pub const FLAT_THIRDS: f64 = 0.003;

/// How far a response's rms is still to move after its window, relative to the last third's,
/// from the rms of the window's thirds r₁, r₂, r₃ ([`whole_period_thirds`]), d₁ = r₂ − r₁,
/// d₂ = r₃ − r₂: where the change slows geometrically (q = d₂/d₁ ∈ (0, 1)), Aitken's Δ² limit
/// r₃ + d₂ q/(1 − q), however small the changes — exact for r_k = r∞ + c q^k, a response
/// approaching its level as e^(−t/τ) (the thirds' means then form a geometric series); where
/// they alternate and the last change is the smaller (q ∈ (−1, 0): a rise that went flat, or a
/// beat), the last change — at 5 275 rpm on 1 mm flanks the rms reads 275.5, 296.6, 295.5 µrad
/// over its thirds (0.37 %) and 297.0, 297.4, 295.5, 295.3 over the last 20 ms in 5 ms blocks,
/// where Aitken's limit for q < 0 would read any beat whose last change is small as settled;
/// where they alternate without shrinking (q ≤ −1), the largest change; where the change does
/// not slow (q ≥ 1: growth), infinite; where both changes are within [`FLAT_THIRDS`], the last
/// change (zero for a response that is zero throughout). A beat whose thirds happen to change
/// little reads as settled: three thirds cannot tell it.
pub fn settling_drift([r1, r2, r3]: [f64; 3]) -> f64 {
    let (d1, d2) = (r2 - r1, r3 - r2);
    if d1.abs().max(d2.abs()) <= FLAT_THIRDS * r3 {
        return match r3 > 0.0 {
            true => d2.abs() / r3,
            false => 0.0,
        };
    }
    let q = d2 / d1;
    match q {
        q if (0.0..1.0).contains(&q) => (d2 * q / (1.0 - q)).abs() / r3,
        q if q < 0.0 && q > -1.0 => d2.abs() / r3,
        q if q <= -1.0 || !q.is_finite() => d1.abs().max(d2.abs()) / r3,
        _ => f64::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn largest_keeps_a_nan() {
        assert!(largest([1.0, f64::NAN, 3.0]).is_nan());
        assert!(largest([f64::NAN, 1.0]).is_nan());
        assert_eq!(largest([1.0, 3.0, 2.0]), 3.0);
        assert_eq!(largest(std::iter::empty()), f64::NEG_INFINITY);
    }

    #[test]
    fn harmonic_amplitudes_read_known_harmonics() {
        // 1 800 Hz with 3 harmonics, a mean and a 2 853 Hz line, sampled at 10 µs (the period,
        // 55.6 samples, is not a whole number of samples).
        let (f, dt) = (1800.0, 1e-5);
        let x: Vec<f64> = (0..1703)
            .map(|k| {
                let t = k as f64 * dt;
                let w = std::f64::consts::TAU * f * t;
                1e-4 + 3e-6 * (w + 0.3).cos()
                    + 2e-6 * (2.0 * w).sin()
                    + 0.5e-6 * (3.0 * w - 1.0).cos()
                    + 1e-6 * (std::f64::consts::TAU * 2853.0 * t).sin()
            })
            .collect();
        let a = harmonic_amplitudes(&x, dt, f, 3);
        // The off-harmonic line leaks O(1/periods) into the harmonics: 30 periods, ≤ 2e-8; the
        // 1e-4 mean, 33 times the largest line, must not leak at all (it did, 4e-8, before the
        // mean was removed).
        for (got, want) in a.iter().zip([3e-6, 2e-6, 0.5e-6]) {
            assert!((got - want).abs() < 2.5e-8, "{got} vs {want}");
        }
        assert_eq!(harmonic_amplitudes(&x[..40], dt, f, 2), vec![0.0, 0.0]);
    }

    #[test]
    fn db5_is_orthonormal_and_invertible() {
        let h = DB5_LOW;
        assert!((h.iter().sum::<f64>() - std::f64::consts::SQRT_2).abs() < 1e-12);
        assert!((h.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12);
        let x: Vec<f64> = (0..64)
            .map(|k| (0.3 * k as f64).sin() + 0.01 * k as f64)
            .collect();
        let (a, d) = dwt_db5(&x);
        let energy: f64 = a.iter().chain(&d).map(|v| v * v).sum();
        assert!((energy / x.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12);
        let back = idwt_db5(&a, &d);
        for (p, q) in x.iter().zip(&back) {
            assert!((p - q).abs() < 1e-12);
        }
    }

    #[test]
    fn spectrum_of_a_sinusoid_at_a_bin() {
        let dt = 1e-4;
        let n = 1000;
        let x: Vec<f64> = (0..n)
            .map(|k| 3.0 + 2.0 * (2.0 * std::f64::consts::PI * 500.0 * k as f64 * dt).sin())
            .collect();
        let s = hann_amplitude_spectrum(&x, dt);
        let peak = s
            .iter()
            .copied()
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert!(
            (peak.0 - 500.0).abs() < 1e-9 && (peak.1 - 2.0).abs() < 1e-9,
            "{peak:?}"
        );
    }

    #[test]
    fn denoising_keeps_a_smooth_signal_and_drops_noise() {
        let n = 1024;
        let smooth: Vec<f64> = (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * k as f64 / 256.0).sin())
            .collect();
        // Deterministic pseudo-noise (LCG), amplitude 0.1.
        let mut seed = 12345_u64;
        let noisy: Vec<f64> = smooth
            .iter()
            .map(|s| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                s + 0.1 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
            })
            .collect();
        let clean = denoise(&noisy, 5);
        let rms = |a: &[f64], b: &[f64]| {
            (a.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
        };
        let before = rms(&noisy, &smooth);
        let after = rms(&clean, &smooth);
        assert!(after < 0.5 * before, "rms error {before} -> {after}");
    }
}
