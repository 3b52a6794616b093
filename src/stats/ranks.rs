//! Average ranks (midranks) with ties.

/// Ranks 1..n of `v`, tied values sharing the mean of their ranks; and the sizes of the tie groups.
pub(crate) fn midranks(v: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut ranks = vec![0.0; v.len()];
    let mut ties = Vec::new();
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let r = (i + j) as f64 / 2.0 + 1.0;
        for &k in &idx[i..=j] {
            ranks[k] = r;
        }
        if j > i {
            ties.push(j - i + 1);
        }
        i = j + 1;
    }
    (ranks, ties)
}

/// sum over tie groups of t^3 - t.
pub(crate) fn tie_sum(ties: &[usize]) -> f64 {
    ties.iter().map(|&t| (t * t * t - t) as f64).sum()
}

#[cfg(test)]
mod tests {
    #[test]
    fn midranks_with_ties() {
        let (r, t) = super::midranks(&[3.0, 1.0, 4.0, 1.0, 5.0]);
        assert_eq!(r, vec![3.0, 1.5, 4.0, 1.5, 5.0]);
        assert_eq!(t, vec![2]);
    }
}
