//! Node distributions along a line: graded interval fractions.

/// Interval end fractions 0 = f₀ < f₁ < … < f_n = 1 along a segment of `length`, with intervals
/// that start at `first` at both ends and grow by `ratio` towards the middle, never above
/// `max_size` (a symmetric geometric grading). At least one interval.
pub fn symmetric_graded_fractions(length: f64, first: f64, ratio: f64, max_size: f64) -> Vec<f64> {
    let first = first.min(length).max(length * 1e-6);
    // Whole intervals from one end while they fit in half the length.
    let mut half = Vec::new();
    let mut covered = 0.0;
    let mut size = first;
    while covered + size <= 0.5 * length {
        half.push(size);
        covered += size;
        size = (size * ratio).min(max_size.max(first));
    }
    // The middle gap becomes its own interval, or is shared by the two middle ones if small.
    let gap = length - 2.0 * covered;
    let mut sizes: Vec<f64> = half.clone();
    match half.last() {
        Some(&last) if gap < 0.5 * last => {
            *sizes.last_mut().expect("non-empty") += 0.5 * gap;
            sizes.extend(half.iter().rev());
            sizes[half.len()] += 0.5 * gap;
        }
        _ => {
            sizes.push(gap);
            sizes.extend(half.iter().rev());
        }
    }
    let total: f64 = sizes.iter().sum();
    let mut fractions = Vec::with_capacity(sizes.len() + 1);
    let mut acc = 0.0;
    fractions.push(0.0);
    for s in &sizes {
        acc += s / total;
        fractions.push(acc);
    }
    *fractions.last_mut().expect("at least one interval") = 1.0;
    fractions
}

/// Quadratic-grid parameters: the corner fractions with a midpoint inserted in every interval
/// (2n + 1 values for n intervals).
pub fn with_midpoints(fractions: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * fractions.len() - 1);
    for w in fractions.windows(2) {
        out.push(w[0]);
        out.push(0.5 * (w[0] + w[1]));
    }
    out.push(*fractions.last().expect("non-empty"));
    out
}

/// `n` equal intervals: fractions k/n.
pub fn uniform_fractions(n: usize) -> Vec<f64> {
    (0..=n).map(|k| k as f64 / n as f64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graded_fractions_are_monotone_symmetric_and_respect_sizes() {
        let f = symmetric_graded_fractions(6.0, 0.25, 1.5, 2.0);
        assert_eq!(f[0], 0.0);
        assert_eq!(*f.last().unwrap(), 1.0);
        let n = f.len() - 1;
        for i in 0..n {
            assert!(f[i + 1] > f[i]);
            let (a, b) = (f[i + 1] - f[i], f[n - i] - f[n - i - 1]);
            assert!((a - b).abs() < 1e-12);
        }
        assert!(((f[1] - f[0]) * 6.0 - 0.25).abs() < 1e-9);
        let g = with_midpoints(&f);
        assert_eq!(g.len(), 2 * n + 1);
        assert!((g[1] - 0.5 * f[1]).abs() < 1e-15);
    }

    #[test]
    fn a_short_segment_gets_one_interval() {
        assert_eq!(
            symmetric_graded_fractions(0.1, 0.25, 1.5, 1.0),
            vec![0.0, 1.0]
        );
    }
}
