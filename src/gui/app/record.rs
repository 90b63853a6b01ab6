//! One computed stage of a run as the app holds it: the newest good value (kept on screen while a
//! newer request runs, and after it fails), the generation it came from, the newest generation
//! requested, and why that request failed. One record per stage (spectra, identification,
//! diagnosis) instead of loose fields.

use std::sync::Arc;

/// A stage's value, generations and error.
#[derive(Debug)]
pub struct StageRecord<T> {
    /// The newest good value.
    pub value: Option<Arc<T>>,
    /// Generation of `value` (0: none yet).
    pub generation: u64,
    /// Newest generation requested (0: none).
    pub requested: u64,
    /// Why the newest request failed, if it did.
    pub error: Option<String>,
}

impl<T> Default for StageRecord<T> {
    fn default() -> Self {
        Self {
            value: None,
            generation: 0,
            requested: 0,
            error: None,
        }
    }
}

impl<T> Clone for StageRecord<T> {
    fn clone(&self) -> Self {
        Self {
            value: self.value.clone(),
            generation: self.generation,
            requested: self.requested,
            error: self.error.clone(),
        }
    }
}

impl<T> StageRecord<T> {
    /// A new request of `generation`: its error, if any, is forgotten.
    pub fn request(&mut self, generation: u64) {
        self.requested = generation;
        self.error = None;
    }

    /// Keeps `value` of `generation` unless an older one than the value shown; returns whether
    /// it was kept (the same generation again is a refit from scratch, and kept).
    pub fn offer(&mut self, generation: u64, value: Arc<T>) -> bool {
        if generation < self.generation {
            return false;
        }
        self.value = Some(value);
        self.generation = generation;
        if generation >= self.requested {
            self.error = None;
        }
        true
    }

    /// The request of `generation` failed: recorded if it is the newest.
    pub fn fail(&mut self, generation: u64, message: String) -> bool {
        if generation < self.requested {
            return false;
        }
        self.error = Some(message);
        true
    }

    /// A request newer than the value shown is under way (and has not failed).
    #[must_use]
    pub fn running(&self) -> bool {
        self.error.is_none() && self.generation < self.requested
    }

    /// The value, as an `Option`.
    #[must_use]
    pub fn as_ref(&self) -> Option<&Arc<T>> {
        self.value.as_ref()
    }

    /// Whether there is a value.
    #[must_use]
    pub fn is_some(&self) -> bool {
        self.value.is_some()
    }

    /// Whether there is none.
    #[must_use]
    pub fn is_none(&self) -> bool {
        self.value.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::StageRecord;
    use std::sync::Arc;

    #[test]
    fn older_results_never_replace_newer_ones_and_errors_follow_the_newest_request() {
        let mut r = StageRecord::<u32>::default();
        r.request(3);
        assert!(r.running());
        assert!(
            r.offer(2, Arc::new(20)),
            "an older request's result is shown until the newest"
        );
        assert!(r.running());
        assert!(r.offer(3, Arc::new(30)));
        assert!(!r.running());
        assert!(!r.offer(2, Arc::new(21)), "stale");
        assert_eq!(r.as_ref().map(|v| **v), Some(30));
        r.request(5);
        assert!(
            !r.fail(4, "old".into()),
            "a failure of an older request is dropped"
        );
        assert!(r.fail(5, "bad".into()));
        assert!(!r.running(), "failed, not running");
        assert_eq!(r.as_ref().map(|v| **v), Some(30), "the last good value stays");
        r.request(6);
        assert!(r.error.is_none());
    }
}
