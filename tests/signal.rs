//! The db5 wavelet transform against PyWavelets (fixture generated once with
//! `pywt.dwt(x, 'db5', mode='periodization')`, PyWavelets 1.x; see tests/fixtures).

use geardyn::signal::{dwt_db5, DB5_LOW};

#[test]
fn db5_matches_pywavelets_periodization() {
    let fixture: serde_json::Value =
        serde_json::from_str(include_str!("fixtures/db5_periodization.json")).unwrap();
    let low: Vec<f64> = serde_json::from_value(fixture["dec_lo"].clone()).unwrap();
    for (a, b) in low.iter().zip(DB5_LOW) {
        assert!((a - b).abs() < 1e-15, "{a} vs {b}");
    }
    for case in fixture["cases"].as_array().unwrap() {
        let n = case["n"].as_u64().unwrap() as usize;
        let x: Vec<f64> = (0..n)
            .map(|k| {
                let k = k as f64;
                (0.37 * k).sin()
                    + 0.5 * (1.9 * k + 0.3).cos()
                    + 0.01 * k
                    + if (k as usize) % 7 == 3 { 0.8 } else { 0.0 }
            })
            .collect();
        let (a, d) = dwt_db5(&x);
        let expected_a: Vec<f64> = serde_json::from_value(case["approximation"].clone()).unwrap();
        let expected_d: Vec<f64> = serde_json::from_value(case["detail"].clone()).unwrap();
        assert_eq!(a.len(), expected_a.len());
        for (p, q) in a.iter().zip(&expected_a).chain(d.iter().zip(&expected_d)) {
            assert!((p - q).abs() < 1e-12, "n = {n}: {p} vs {q}");
        }
    }
}

/// A quasi-static contact-force record as the paper's 60 rpm scene has it: a 10 ms ramp to the
/// full load F = T/r_b2, then a slow 5 % variation at the mesh frequency (36 Hz), sampled every
/// 10 µs for 0.1 s, ending at full load.
fn quasi_static_force(load: f64) -> Vec<f64> {
    (0..=10_000)
        .map(|k| {
            let t = k as f64 * 1e-5;
            let ramp = (t / 0.01).min(1.0);
            load * ramp * (1.0 + 0.05 * (std::f64::consts::TAU * 36.0 * t).sin())
        })
        .collect()
}

/// No impact, no detail: below 1 % of the load everywhere, ends included. (Periodized alone,
/// the transform joins the end at full load to the start at zero: 0.44 × the load.)
#[test]
fn a_quasi_static_force_record_has_no_level1_detail() {
    use geardyn::signal::{dwt_db5, level1_detail_max};
    let load = 2670.0;
    let force = quasi_static_force(load);
    let largest = level1_detail_max(&force, 0);
    assert!(largest < 0.01 * load, "{largest} N");
    let (_, periodized) = dwt_db5(&force);
    let wrapped = periodized.iter().map(|d| d.abs()).fold(0.0, f64::max);
    assert!(
        wrapped > 0.4 * load,
        "the wrap-around this guards against: {wrapped} N"
    );
}

/// An impact one sample (10 µs) wide of size A on the quasi-static record: its largest level-1
/// detail is A times the largest db5 high-pass tap that meets it — |g_j| over the taps j of the
/// other parity than the sample (j + k odd) — to round-off; nothing else in the record comes
/// near it.
#[test]
fn an_impact_of_known_size_gives_its_level1_detail() {
    use geardyn::signal::{db5_high, level1_detail, level1_detail_max};
    let (load, size) = (2670.0, 500.0);
    for k in [6000_usize, 6001] {
        let mut force = quasi_static_force(load);
        force[k] += size;
        let tap = (0..10)
            .filter(|j| (j + k) % 2 == 1)
            .map(|j| db5_high()[j].abs())
            .fold(0.0, f64::max);
        let expected = size * tap;
        let largest = level1_detail_max(&force, 0);
        assert!(
            (largest - expected).abs() < 1e-6 * expected,
            "impact at sample {k}: {largest} N against {expected} N"
        );
        let detail = level1_detail(&force);
        let at = detail
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .unwrap()
            .0;
        assert!(
            at.abs_diff(k) <= 1,
            "the largest detail at {at}, the impact at {k}"
        );
        // Over a window that starts after the impact, it is gone.
        assert!(level1_detail_max(&force, k + 8) < 0.01 * load);
    }
}

/// Impacts of known size A and width: half-sines A sin(πn/w), n = 0 … w, spread over w samples
/// (10 µs each). The transform is linear, so the record's detail minus the quasi-static record's
/// is the impact's own, which a direct convolution with the db5 high-pass taps gives apart from
/// the transform's reflection and indexing:
/// d_i = Σ_j g_j x_{2i+1−j} (the parity the one-sample test pins down). The level-1 band
/// (25–50 kHz) reads an impact's fast content, not its size: A·|g| for one sample, and it
/// falls as the impact widens — below 5 % of A for an impact 100 µs wide (362, 165, 118, 25 and
/// 13 N of 500 N at 2, 3, 5, 10 and 20 samples).
#[test]
fn wider_impacts_give_the_detail_of_their_fast_content() {
    use geardyn::signal::{db5_high, level1_detail};
    let (load, size, at) = (2670.0, 500.0, 6000_usize);
    let quasi_static = level1_detail(&quasi_static_force(load));
    let mut previous = f64::INFINITY;
    for width in [2_usize, 3, 5, 10, 20] {
        let impact: Vec<f64> = (0..=width)
            .map(|n| size * (std::f64::consts::PI * n as f64 / width as f64).sin())
            .collect();
        let mut force = quasi_static_force(load);
        for (n, f) in impact.iter().enumerate() {
            force[at + n] += f;
        }
        let own = level1_detail(&force)
            .iter()
            .zip(&quasi_static)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Direct convolution of the impact alone (zero elsewhere), on the same parity.
        let sample = |k: i64| {
            let n = k - at as i64;
            if (0..=width as i64).contains(&n) {
                impact[n as usize]
            } else {
                0.0
            }
        };
        let expected = (at as i64 / 2 - 10..(at + width) as i64 / 2 + 10)
            .map(|i| {
                (0..10)
                    .map(|j| db5_high()[j] * sample(2 * i + 1 - j as i64))
                    .sum::<f64>()
                    .abs()
            })
            .fold(0.0, f64::max);
        assert!(
            (own - expected).abs() < 1e-9 * size,
            "width {width}: {own} N against {expected} N"
        );
        assert!(own < previous, "width {width}: {own} N after {previous} N");
        if width == 10 {
            assert!(own < 0.05 * size, "100 µs wide: {own} N");
        }
        if width == 20 {
            // Wider than the filter, level 1 sees only the kinks at the impact's ends, slope
            // jumps of Aπ/w: doubling the width halves the detail.
            assert!(
                (own / previous - 0.5).abs() < 0.03,
                "{own} N after {previous} N"
            );
        }
        previous = own;
    }
}
