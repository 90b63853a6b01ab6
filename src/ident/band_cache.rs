//! A value derived from a block's spectra (or their factorisation) for one band, kept with them
//! for the last [`BANDS_KEPT`] bands asked: it does not depend on A, Lambda or the order, so a
//! retune reuses it. Kept with the spectra: the stretches' fits, the held-out figures, the usable
//! band (keyed by the auto search's limits); with the factorisation: the warnings' near-singular
//! counts. More than one band because one identification may ask for two (the usable band, then
//! the band ended at a misfit at its top, `super::band_top`): with one entry each would evict the
//! other, and every retune would recompute both. The key is the band's exact bits; a poisoned
//! lock is a miss (the value is recomputed, never lost to a panic). A copy of the spectra or the
//! factorisation carries its caches: one whose data are then changed needs empty ones.

use std::sync::{Arc, Mutex};

/// Bands kept per cache.
pub const BANDS_KEPT: usize = 4;

/// The band's bits and the value found for it (`None`: nothing could be computed for that band).
type Entry<T> = ([u64; 2], Option<Arc<T>>);

/// One value per block's spectra and band, for the last [`BANDS_KEPT`] bands asked (the most
/// recently asked first).
#[derive(Debug)]
pub struct BandCache<T>(Mutex<Vec<Entry<T>>>);

impl<T> Default for BandCache<T> {
    fn default() -> Self {
        Self(Mutex::new(Vec::new()))
    }
}

impl<T> Clone for BandCache<T> {
    fn clone(&self) -> Self {
        Self(Mutex::new(self.0.lock().map(|g| g.clone()).unwrap_or_default()))
    }
}

impl<T> BandCache<T> {
    /// The value for `band_hz`: the cached one when the band is among the last asked, else
    /// `compute()` (kept for the next calls, the oldest band dropped).
    pub fn get_or(&self, band_hz: [f64; 2], compute: impl FnOnce() -> Option<T>) -> Option<Arc<T>> {
        let key = band_hz.map(f64::to_bits);
        if let Lookup::Found(value) = self.hit(key) {
            return value;
        }
        let value = compute().map(Arc::new);
        self.keep(key, value.clone());
        value
    }

    /// [`Self::get_or`] for a value that can always be computed: a band cached as "nothing"
    /// (by `get_or`) is computed again.
    pub fn get_or_insert_with(&self, band_hz: [f64; 2], compute: impl FnOnce() -> T) -> Arc<T> {
        let key = band_hz.map(f64::to_bits);
        if let Lookup::Found(Some(value)) = self.hit(key) {
            return value;
        }
        let value = Arc::new(compute());
        self.keep(key, Some(Arc::clone(&value)));
        value
    }

    /// The entry for `key`, moved to the front; a miss on a band not kept or a poisoned lock.
    fn hit(&self, key: [u64; 2]) -> Lookup<T> {
        let Ok(mut guard) = self.0.lock() else {
            return Lookup::Miss;
        };
        let Some(i) = guard.iter().position(|(k, _)| *k == key) else {
            return Lookup::Miss;
        };
        let entry = guard.remove(i);
        let value = entry.1.clone();
        guard.insert(0, entry);
        Lookup::Found(value)
    }

    /// Keeps `value` for `key` in front, the oldest band dropped past [`BANDS_KEPT`].
    fn keep(&self, key: [u64; 2], value: Option<Arc<T>>) {
        if let Ok(mut guard) = self.0.lock() {
            guard.retain(|(k, _)| *k != key);
            guard.insert(0, (key, value));
            guard.truncate(BANDS_KEPT);
        }
    }
}

/// What the cache holds for a band: not kept (a miss), or kept, as a value or as "nothing".
enum Lookup<T> {
    Miss,
    Found(Option<Arc<T>>),
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use super::BandCache;

    #[test]
    fn a_band_is_computed_once_while_it_is_among_the_last_asked() {
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
        // Two bands asked in turn (the usable band, then the band ended at a misfit): both kept.
        assert_eq!(cache.get_or([0.1, 10.0], || compute(5.0)).as_deref(), Some(&1.0));
        assert_eq!(cache.get_or([0.1, 12.0], || compute(6.0)).as_deref(), Some(&3.0));
        assert_eq!(calls.get(), 2, "neither evicts the other");
        let copy = cache.clone();
        assert_eq!(copy.get_or([0.1, 12.0], || compute(4.0)).as_deref(), Some(&3.0));
        assert_eq!(calls.get(), 2, "a clone keeps the cached value");
        // The oldest of more than BANDS_KEPT bands is dropped.
        for top in 0..super::BANDS_KEPT {
            let _ = cache.get_or([0.2, 20.0 + top as f64], || compute(7.0));
        }
        assert_eq!(calls.get(), 2 + super::BANDS_KEPT);
        assert_eq!(cache.get_or([0.1, 10.0], || compute(8.0)).as_deref(), Some(&8.0));
    }

    #[test]
    fn an_always_computed_value_is_computed_once_and_replaces_nothing() {
        let cache = BandCache::<usize>::default();
        let calls = Cell::new(0);
        let compute = |v: usize| {
            calls.set(calls.get() + 1);
            v
        };
        assert_eq!(*cache.get_or_insert_with([0.1, 10.0], || compute(1)), 1);
        assert_eq!(*cache.get_or_insert_with([0.1, 10.0], || compute(2)), 1);
        assert_eq!(calls.get(), 1, "the same band is not recomputed");
        // A band kept as "nothing" by get_or is computed when a value is required.
        assert_eq!(cache.get_or([0.2, 5.0], || None), None);
        assert_eq!(*cache.get_or_insert_with([0.2, 5.0], || compute(3)), 3);
        assert_eq!(cache.get_or([0.2, 5.0], || Some(4)).as_deref(), Some(&3));
        assert_eq!(calls.get(), 2);
    }
}
