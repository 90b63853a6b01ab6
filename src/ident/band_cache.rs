//! A value derived from a block's spectra for one band, kept with the spectra for the last band
//! asked: it does not depend on A, Lambda or the order, so a retune reuses it. The key is the
//! band's exact bits; a poisoned lock is a miss (the value is recomputed, never lost to a panic).

use std::sync::{Arc, Mutex};

/// The band's bits and the value found for it (`None`: nothing could be computed for that band).
type Entry<T> = ([u64; 2], Option<Arc<T>>);

/// One value per block's spectra, for the last band asked.
#[derive(Debug)]
pub struct BandCache<T>(Mutex<Option<Entry<T>>>);

impl<T> Default for BandCache<T> {
    fn default() -> Self {
        Self(Mutex::new(None))
    }
}

impl<T> Clone for BandCache<T> {
    fn clone(&self) -> Self {
        Self(Mutex::new(self.0.lock().ok().and_then(|g| g.clone())))
    }
}

impl<T> BandCache<T> {
    /// The value for `band_hz`: the cached one when the band is the last asked, else `compute()`
    /// (kept for the next call).
    pub fn get_or(&self, band_hz: [f64; 2], compute: impl FnOnce() -> Option<T>) -> Option<Arc<T>> {
        let key = band_hz.map(f64::to_bits);
        if let Ok(guard) = self.0.lock()
            && let Some((k, value)) = guard.as_ref()
            && *k == key
        {
            return value.clone();
        }
        let value = compute().map(Arc::new);
        if let Ok(mut guard) = self.0.lock() {
            *guard = Some((key, value.clone()));
        }
        value
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use super::BandCache;

    #[test]
    fn a_band_is_computed_once_until_another_band_is_asked() {
        let cache = BandCache::<f64>::default();
        let calls = Cell::new(0);
        let compute = |v: f64| {
            calls.set(calls.get() + 1);
            Some(v)
        };
        assert_eq!(cache.get_or([0.1, 10.0], || compute(1.0)).as_deref(), Some(&1.0));
        assert_eq!(cache.get_or([0.1, 10.0], || compute(2.0)).as_deref(), Some(&1.0));
        assert_eq!(calls.get(), 1, "the same band is not recomputed");
        assert_eq!(cache.get_or([0.1, 12.0], || compute(3.0)).as_deref(), Some(&3.0));
        assert_eq!(calls.get(), 2, "another band is computed");
        let copy = cache.clone();
        assert_eq!(copy.get_or([0.1, 12.0], || compute(4.0)).as_deref(), Some(&3.0));
        assert_eq!(calls.get(), 2, "a clone keeps the cached value");
    }
}
