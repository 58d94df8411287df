//! The mesh stiffness, the one currency of the chain: k(θ) and the unloaded transmission error
//! e(θ) over one mesh period of driver roll angle θ, the load they hold at, and their source.
//!
//! Every source builds it (the LTCA, the potential-energy method, ISO 6336-1, the explicit FE's
//! DTE, a CSV file) and every consumer reads it (the lumped model, the sweeps, the reports).
//!
//! # The file format
//! CSV with the columns `roll_angle_deg` (driver roll angle over one mesh period, increasing,
//! the end point not repeated), `mesh_stiffness_n_per_m`, and optionally `unloaded_te_um`
//! (unloaded transmission error along the line of action, positive when the driven gear lags)
//! and `load_torque_nm`. Other columns are ignored, so an LTCA position table is itself a valid
//! stiffness file. Opening files is the IO edge's job ([`crate::report::stiffness_csv`]); this
//! module formats and parses.

use std::io::Read;

/// A periodic function of the driver roll angle, sampled uniformly on one period (linear
/// interpolation between samples, the last joining the first one period later).
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicTable {
    /// Period in roll angle [rad] (2π/z₁ for mesh quantities).
    pub period: f64,
    /// Values at θ = j·period/N, j = 0 … N−1.
    pub values: Vec<f64>,
}

impl PeriodicTable {
    pub fn constant(period: f64, value: f64) -> Self {
        Self {
            period,
            values: vec![value],
        }
    }

    /// Samples `f` at N points of one period.
    pub fn from_fn(period: f64, samples: usize, f: impl Fn(f64) -> f64) -> Self {
        Self {
            period,
            values: (0..samples)
                .map(|j| f(j as f64 * period / samples as f64))
                .collect(),
        }
    }

    /// Resamples an increasing, non-uniform set of samples (θᵢ, vᵢ) of one period onto a
    /// uniform table of as many points, starting at θ₀, by periodic linear interpolation (the
    /// last sample joins the first one period later). Errors name what is wrong.
    pub fn from_samples(period: f64, angles: &[f64], values: &[f64]) -> Result<Self, String> {
        let n = angles.len();
        if n == 0 || n != values.len() {
            return Err(format!(
                "{n} angles and {} values: give one value per angle, at least one",
                values.len()
            ));
        }
        if let Some(i) = (1..n).find(|&i| !(angles[i] > angles[i - 1])) {
            return Err(format!(
                "angles must increase strictly: row {} ({}) follows {}",
                i + 1,
                angles[i],
                angles[i - 1]
            ));
        }
        if !(angles[n - 1] - angles[0] < period) {
            return Err(format!(
                "the angles span {} rad, not less than one period ({period} rad): give one mesh period without repeating its end",
                angles[n - 1] - angles[0]
            ));
        }
        let value_at = |theta: f64| {
            let u = theta - angles[0];
            let i = angles.partition_point(|a| *a - angles[0] <= u).max(1) - 1;
            let (a0, v0) = (angles[i] - angles[0], values[i]);
            let (a1, v1) = if i + 1 < n {
                (angles[i + 1] - angles[0], values[i + 1])
            } else {
                (period, values[0])
            };
            v0 + (v1 - v0) * (u - a0) / (a1 - a0)
        };
        Ok(Self::from_fn(period, n, |theta| {
            value_at(angles[0] + theta)
        }))
    }

    pub fn mean(&self) -> f64 {
        self.values.iter().sum::<f64>() / self.values.len() as f64
    }

    pub fn min(&self) -> f64 {
        self.values.iter().copied().fold(f64::INFINITY, f64::min)
    }

    pub fn max(&self) -> f64 {
        self.values
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Value at roll angle θ measured from the first sample (any θ; periodic, linear between
    /// samples).
    pub fn at(&self, theta: f64) -> f64 {
        let n = self.values.len();
        if n == 1 {
            return self.values[0];
        }
        let u = (theta / self.period).rem_euclid(1.0) * n as f64;
        let i = (u.floor() as usize).min(n - 1);
        let t = u - i as f64;
        self.values[i] * (1.0 - t) + self.values[(i + 1) % n] * t
    }
}

/// The mesh stiffness of a pair over one mesh period: k(θ) [N/m] and the unloaded transmission
/// error e(θ) [m] along the line of action, θ the driver roll angle from `origin`.
///
/// The mesh force of the lumped model is W = k(θ)·(δ − e(θ)) with δ the transmission error
/// along the line of action (seed paper eq. 37 read the other way: k = W/(R_b2 θ_DTE − e)).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshStiffness {
    /// Where it comes from, for outputs ("ltca (relief none)", "potential-energy", …).
    pub source: String,
    /// Load torque on the driven gear it was computed at [N·m]; `None` for load-independent
    /// models and files that do not say.
    pub load_torque: Option<f64>,
    /// Driver roll angle of the first sample [rad] (the tables' θ = 0).
    pub origin: f64,
    /// Mesh stiffness k(θ) [N/m].
    pub stiffness: PeriodicTable,
    /// Unloaded transmission error e(θ) along the line of action [m].
    pub unloaded_te: PeriodicTable,
}

impl MeshStiffness {
    /// From two tables of the same period, origin 0.
    pub fn from_tables(
        source: impl Into<String>,
        load_torque: Option<f64>,
        stiffness: PeriodicTable,
        unloaded_te: PeriodicTable,
    ) -> Self {
        debug_assert_eq!(stiffness.period, unloaded_te.period);
        Self {
            source: source.into(),
            load_torque,
            origin: 0.0,
            stiffness,
            unloaded_te,
        }
    }

    /// A constant stiffness and no unloaded TE.
    pub fn constant(source: impl Into<String>, period: f64, stiffness: f64) -> Self {
        Self::from_tables(
            source,
            None,
            PeriodicTable::constant(period, stiffness),
            PeriodicTable::constant(period, 0.0),
        )
    }

    /// From samples at increasing roll angles spanning less than one `period` (resampled onto a
    /// uniform table of as many points from the first angle). Errors say what is wrong.
    pub fn from_samples(
        source: impl Into<String>,
        load_torque: Option<f64>,
        period: f64,
        roll_angles: &[f64],
        stiffness: &[f64],
        unloaded_te: &[f64],
    ) -> Result<Self, String> {
        Ok(Self {
            source: source.into(),
            load_torque,
            origin: roll_angles.first().copied().unwrap_or(0.0),
            stiffness: PeriodicTable::from_samples(period, roll_angles, stiffness)?,
            unloaded_te: PeriodicTable::from_samples(period, roll_angles, unloaded_te)?,
        })
    }

    /// The stiffness with a compliance `c` [m/N] taken out of series: k' = 1/(1/k − c) (e kept).
    /// `None` when c is not below every 1/k.
    pub fn without_series_compliance(&self, c: f64) -> Option<Self> {
        let mut out = self.clone();
        for k in &mut out.stiffness.values {
            let rest = 1.0 / *k - c;
            if !(rest > 0.0) {
                return None;
            }
            *k = 1.0 / rest;
        }
        out.source = format!("{} without {c:.3e} m/N body twist", self.source);
        Some(out)
    }

    /// The mesh period in driver roll angle [rad].
    pub fn period(&self) -> f64 {
        self.stiffness.period
    }

    /// Mean stiffness over the period k̄ [N/m].
    pub fn mean(&self) -> f64 {
        self.stiffness.mean()
    }

    /// The same k(θ) scaled to the mean `mean` [N/m]: its shape, e(θ) and origin kept.
    pub fn scaled_to_mean(&self, mean: f64) -> Self {
        let mut scaled = self.clone();
        let ratio = mean / self.mean();
        for k in scaled.stiffness.values.iter_mut() {
            *k *= ratio;
        }
        scaled.source = format!("{} scaled to the mean {mean:.4e} N/m", self.source);
        scaled
    }

    pub fn min(&self) -> f64 {
        self.stiffness.min()
    }

    pub fn max(&self) -> f64 {
        self.stiffness.max()
    }

    /// Samples of one period: (driver roll angle [rad], k [N/m], e [m]) at the finer of the two
    /// tables' spacings.
    pub fn samples(&self) -> Vec<(f64, f64, f64)> {
        let n = self
            .stiffness
            .values
            .len()
            .max(self.unloaded_te.values.len());
        (0..n)
            .map(|j| {
                let theta = j as f64 * self.period() / n as f64;
                (
                    self.origin + theta,
                    self.stiffness.at(theta),
                    self.unloaded_te.at(theta),
                )
            })
            .collect()
    }

    /// The file format (see the module doc), every number with 9 significant decimals.
    pub fn to_csv(&self) -> String {
        let mut text = String::from("roll_angle_deg,mesh_stiffness_n_per_m,unloaded_te_um");
        if self.load_torque.is_some() {
            text.push_str(",load_torque_nm");
        }
        text.push('\n');
        for (theta, k, e) in self.samples() {
            text.push_str(&format!(
                "{:.9},{:.9e},{:.9}",
                theta.to_degrees(),
                k,
                e * 1e6
            ));
            if let Some(t) = self.load_torque {
                text.push_str(&format!(",{t}"));
            }
            text.push('\n');
        }
        text
    }

    /// Parses the file format from `reader` for a mesh of period `period` [rad]; `name` names
    /// the file in messages, which say what is wrong and where.
    pub fn from_csv(
        reader: impl Read,
        name: &str,
        period: f64,
        source: impl Into<String>,
    ) -> Result<Self, String> {
        let mut reader = csv::Reader::from_reader(reader);
        let header = reader
            .headers()
            .map_err(|e| format!("{name}: no header row: {e}"))?
            .clone();
        let column = |key: &str| header.iter().position(|h| h.trim() == key);
        let (Some(angle_col), Some(k_col)) =
            (column("roll_angle_deg"), column("mesh_stiffness_n_per_m"))
        else {
            return Err(format!(
                "{name}: needs the columns roll_angle_deg and mesh_stiffness_n_per_m (found: {})",
                header.iter().collect::<Vec<_>>().join(", ")
            ));
        };
        let (te_col, torque_col) = (column("unloaded_te_um"), column("load_torque_nm"));
        let (mut angles, mut k, mut te) = (Vec::new(), Vec::new(), Vec::new());
        let mut torque = None;
        for (row, record) in reader.records().enumerate() {
            let record = record.map_err(|e| format!("{name}: {e}"))?;
            let line = row + 2;
            let number = |col: usize, key: &str| -> Result<f64, String> {
                let text = record.get(col).unwrap_or("").trim();
                text.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        format!("{name} line {line}: {key} = {text:?} is not a finite number")
                    })
            };
            angles.push(number(angle_col, "roll_angle_deg")?.to_radians());
            let stiffness = number(k_col, "mesh_stiffness_n_per_m")?;
            if !(stiffness > 0.0) {
                return Err(format!(
                    "{name} line {line}: mesh_stiffness_n_per_m = {stiffness} must be > 0 (teeth always in contact; separation is the model's job)"
                ));
            }
            k.push(stiffness);
            te.push(match te_col {
                Some(c) => number(c, "unloaded_te_um")? * 1e-6,
                None => 0.0,
            });
            if let Some(c) = torque_col {
                torque = Some(number(c, "load_torque_nm")?);
            }
        }
        Self::from_samples(source, torque, period, &angles, &k, &te).map_err(|e| {
            format!(
                "{name}: {e} (the mesh period is {:.6} deg of driver roll angle)",
                period.to_degrees()
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Written and read back, a table keeps its samples (to the file's 9 decimals), its origin
    /// and its load.
    #[test]
    fn csv_round_trip_keeps_samples_origin_and_load() {
        let period = std::f64::consts::TAU / 36.0;
        let angles: Vec<f64> = (0..16).map(|j| 0.3 + j as f64 * period / 16.0).collect();
        let k: Vec<f64> = (0..16).map(|j| 4e8 + 1e7 * j as f64).collect();
        let e: Vec<f64> = (0..16).map(|j| 1e-6 * (j as f64).sin()).collect();
        let table =
            MeshStiffness::from_samples("test", Some(143.6), period, &angles, &k, &e).unwrap();
        let text = table.to_csv();
        let back = MeshStiffness::from_csv(text.as_bytes(), "t.csv", period, "csv").unwrap();
        assert_eq!(back.load_torque, Some(143.6));
        assert!((back.origin - 0.3).abs() < 1e-9);
        for j in 0..16 {
            assert!((back.stiffness.values[j] / k[j] - 1.0).abs() < 1e-9);
            assert!((back.unloaded_te.values[j] - e[j]).abs() < 1e-14);
        }
    }

    #[test]
    fn a_table_longer_than_a_period_is_refused_with_the_period() {
        let period = 0.1;
        let text = "roll_angle_deg,mesh_stiffness_n_per_m\n0,4e8\n3,4e8\n6,4e8\n";
        let err = MeshStiffness::from_csv(text.as_bytes(), "k.csv", period, "csv").unwrap_err();
        assert!(err.contains("k.csv") && err.contains("period"), "{err}");
    }
}
