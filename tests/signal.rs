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
