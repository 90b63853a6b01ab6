//! Densities averaged over bands (the observer's angle-noise model, the reference's noise): which
//! band holds a frequency.
//!
//! Bands are given by their ascending edges, Hz: band `b` is `[edges[b], edges[b + 1])`, and the
//! last band holds its top edge too. A frequency below the first edge, above the last, or NaN is
//! in no band; fewer than two edges make no band.

/// The index of the band of `edges_hz` holding `f_hz` (module docs), `None` outside them.
#[must_use]
pub fn band_holding(edges_hz: &[f64], f_hz: f64) -> Option<usize> {
    let last = edges_hz.len().checked_sub(2)?;
    if edges_hz.last() == Some(&f_hz) {
        return Some(last);
    }
    let b = edges_hz.partition_point(|&e| e <= f_hz);
    (1..=last + 1).contains(&b).then(|| b - 1)
}

#[cfg(test)]
mod tests {
    use super::band_holding;

    /// Against a linear search of the definition, on and between the edges and outside them.
    #[test]
    fn the_band_holding_a_frequency_is_found() {
        let edges = [0.5, 1.0, 2.0, 4.0];
        let naive = |f: f64| {
            (0..edges.len() - 1).find(|&b| {
                (edges[b] <= f && f < edges[b + 1]) || (b == edges.len() - 2 && edges.last() == Some(&f))
            })
        };
        for f in [
            0.0,
            0.4999,
            0.5,
            0.7,
            1.0,
            1.5,
            2.0,
            3.999,
            4.0,
            4.0001,
            10.0,
            f64::NAN,
        ] {
            assert_eq!(band_holding(&edges, f), naive(f), "{f}");
        }
        assert_eq!(band_holding(&edges, 4.0), Some(2));
        assert_eq!(band_holding(&edges, 0.5), Some(0));
        assert_eq!(band_holding(&[1.0], 1.0), None);
        assert_eq!(band_holding(&[], 1.0), None);
    }
}
