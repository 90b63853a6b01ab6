//! The error panel's log: one entry per distinct failure (a repeat moves it to the end and counts
//! it, instead of a second line), each tagged with what failed, so that a later success of the
//! same thing clears it (a fixed error does not stay on screen).

use super::RunId;

/// What an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorTopic {
    /// A file that could not be loaded (stays until dismissed).
    Load,
    /// A run's analysis (spectra, identification): cleared by its next success.
    Analysis(RunId),
    /// A run's diagnosis: cleared by its next success.
    Diagnosis(RunId),
    /// The Validation tab's prediction of a run.
    Validation(RunId),
    /// A model or view export (stays until dismissed).
    Export,
}

/// One line of the panel.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorEntry {
    /// What failed.
    pub topic: ErrorTopic,
    /// The message.
    pub message: String,
    /// How many times it happened.
    pub count: usize,
}

impl ErrorEntry {
    /// The line shown: the message, with the count when it repeated.
    #[must_use]
    pub fn line(&self) -> String {
        if self.count > 1 {
            format!("{} (x{})", self.message, self.count)
        } else {
            self.message.clone()
        }
    }
}

/// The panel's entries, oldest first.
#[derive(Clone, Debug, Default)]
pub struct ErrorLog {
    entries: Vec<ErrorEntry>,
}

impl ErrorLog {
    /// Records a failure; a repeat of an entry moves it to the end with its count raised.
    pub fn push(&mut self, topic: ErrorTopic, message: String) {
        let mut entry = ErrorEntry {
            topic,
            message,
            count: 1,
        };
        if let Some(i) = self
            .entries
            .iter()
            .position(|e| e.topic == topic && e.message == entry.message)
        {
            entry.count += self.entries.remove(i).count;
        }
        self.entries.push(entry);
    }

    /// Clears every entry about `topic` (it has since succeeded).
    pub fn clear(&mut self, topic: ErrorTopic) {
        self.entries.retain(|e| e.topic != topic);
    }

    /// Removes entry `index` (out of range: nothing).
    pub fn dismiss(&mut self, index: usize) {
        if index < self.entries.len() {
            self.entries.remove(index);
        }
    }

    /// The entries, oldest first.
    #[must_use]
    pub fn entries(&self) -> &[ErrorEntry] {
        &self.entries
    }

    /// The lines shown, oldest first.
    #[must_use]
    pub fn lines(&self) -> Vec<String> {
        self.entries.iter().map(ErrorEntry::line).collect()
    }

    /// No entry.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::{ErrorLog, ErrorTopic};

    #[test]
    fn repeats_are_counted_and_a_success_clears_its_topic() {
        let mut log = ErrorLog::default();
        log.push(ErrorTopic::Analysis(1), "a.csv: spectra stage: too short".into());
        log.push(ErrorTopic::Load, "b.csv: line 3: bad".into());
        log.push(ErrorTopic::Analysis(1), "a.csv: spectra stage: too short".into());
        log.push(ErrorTopic::Analysis(1), "a.csv: spectra stage: too short".into());
        assert_eq!(
            log.lines(),
            vec!["b.csv: line 3: bad", "a.csv: spectra stage: too short (x3)"]
        );
        log.push(ErrorTopic::Diagnosis(1), "a.csv: diagnosis: short".into());
        log.clear(ErrorTopic::Analysis(1));
        assert_eq!(log.lines(), vec!["b.csv: line 3: bad", "a.csv: diagnosis: short"]);
        log.dismiss(7);
        log.dismiss(0);
        assert_eq!(log.lines(), vec!["a.csv: diagnosis: short"]);
        log.clear(ErrorTopic::Diagnosis(2));
        assert!(!log.is_empty(), "another run's success clears nothing here");
    }
}
