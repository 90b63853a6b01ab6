//! A small argument parser: positionals plus `--name value` / `--name=value` options, each option
//! possibly repeated. Unknown or missing options are reported in one line by the commands.

use std::str::FromStr;

use super::CliError;

/// Parsed arguments of one command.
#[derive(Debug, Default)]
pub struct Args {
    /// Positional arguments, in order.
    pub positional: Vec<String>,
    options: Vec<(String, String)>,
    used: std::cell::RefCell<Vec<String>>,
}

impl Args {
    /// Splits `argv` into positionals and options. Every option takes a value.
    ///
    /// # Errors
    /// An option without a value.
    pub fn parse(argv: &[String]) -> Result<Self, CliError> {
        Self::parse_with_flags(argv, &[])
    }

    /// [`Args::parse`], where the options named in `flags` take no value (`--diagnose`).
    ///
    /// # Errors
    /// An option without a value.
    pub fn parse_with_flags(argv: &[String], flags: &[&str]) -> Result<Self, CliError> {
        let mut args = Args::default();
        let mut it = argv.iter();
        while let Some(a) = it.next() {
            if let Some(name) = a.strip_prefix("--") {
                let (name, value) = if let Some((n, v)) = name.split_once('=') {
                    (n.to_owned(), v.to_owned())
                } else if flags.contains(&name) {
                    (name.to_owned(), "true".to_owned())
                } else {
                    let v = it
                        .next()
                        .ok_or_else(|| CliError::Input(format!("option --{name} needs a value")))?;
                    (name.to_owned(), v.clone())
                };
                args.options.push((name, value));
            } else {
                args.positional.push(a.clone());
            }
        }
        Ok(args)
    }

    /// Every value given for `--name`.
    #[must_use]
    pub fn all(&self, name: &str) -> Vec<&str> {
        self.used.borrow_mut().push(name.to_owned());
        self.options
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
            .collect()
    }

    /// The value of `--name`, if given (the last one wins).
    ///
    /// # Errors
    /// None today; kept fallible so commands treat every option alike.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.all(name).last().copied()
    }

    /// Whether the flag `--name` was given (see [`Args::parse_with_flags`]).
    #[must_use]
    pub fn flag(&self, name: &str) -> bool {
        self.get(name).is_some_and(|v| v != "false")
    }

    /// The value of `--name` parsed as `T`, or `default`.
    ///
    /// # Errors
    /// A value that does not parse, named in the message.
    pub fn parsed_or<T: FromStr>(&self, name: &str, default: T) -> Result<T, CliError>
    where
        T::Err: std::fmt::Display,
    {
        match self.get(name) {
            None => Ok(default),
            Some(v) => v
                .parse()
                .map_err(|e| CliError::Input(format!("--{name} {v}: {e}"))),
        }
    }

    /// The value of a required `--name`.
    ///
    /// # Errors
    /// When it is missing.
    pub fn required(&self, name: &str) -> Result<&str, CliError> {
        self.get(name)
            .ok_or_else(|| CliError::Input(format!("missing --{name}")))
    }

    /// Fails on options no command asked about (call after reading every option).
    ///
    /// # Errors
    /// The first unknown option.
    pub fn reject_unknown(&self) -> Result<(), CliError> {
        let used = self.used.borrow();
        match self.options.iter().find(|(n, _)| !used.contains(n)) {
            Some((n, _)) => Err(CliError::Input(format!("unknown option --{n}"))),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_owned).collect()
    }

    #[test]
    fn options_positionals_and_repeats() {
        let a = Args::parse(&argv("run.csv --out=m.json --effect a --effect b:gyro other")).unwrap();
        assert_eq!(a.positional, vec!["run.csv", "other"]);
        assert_eq!(a.get("out"), Some("m.json"));
        assert_eq!(a.all("effect"), vec!["a", "b:gyro"]);
        assert!(a.reject_unknown().is_ok());
        assert_eq!(a.parsed_or("seed", 5u64).unwrap(), 5);
    }

    #[test]
    fn errors_are_single_lines() {
        assert!(matches!(Args::parse(&argv("--out")), Err(CliError::Input(m)) if m.contains("--out")));
        let a = Args::parse(&argv("--sede 3")).unwrap();
        assert!(matches!(a.reject_unknown(), Err(CliError::Input(m)) if m == "unknown option --sede"));
        let a = Args::parse(&argv("--seed x")).unwrap();
        assert!(matches!(a.parsed_or("seed", 1u64), Err(CliError::Input(m)) if m.starts_with("--seed x")));
    }
}
