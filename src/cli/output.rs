//! Shared output plumbing of the CLI: JSON on stdout, human text, progress bars (files: `super::files`).

use std::io::Write;
use std::time::Duration;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};

/// The output flags most commands share.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct OutputArgs {
    /// Print JSON on stdout instead of text: one object (one per line where the command says so: `cull --eyes`).
    #[arg(long)]
    pub json: bool,
    /// No progress bars or human-readable text (errors and warnings are still printed).
    #[arg(long, short)]
    pub quiet: bool,
}

impl From<OutputArgs> for Output {
    fn from(a: OutputArgs) -> Output {
        Output {
            json: a.json,
            quiet: a.quiet,
            quiet_text: false,
        }
    }
}

/// How a command reports: human text, one JSON object on stdout, or nothing but errors.
#[derive(Clone, Copy, Debug)]
pub struct Output {
    /// Print one JSON object on stdout instead of text.
    pub json: bool,
    /// No progress bars and no human text.
    pub quiet: bool,
    /// No human text on stdout (an output goes there: `-o -`); progress bars stay on stderr.
    pub quiet_text: bool,
}

impl Output {
    /// Refuses `-q` without `--json` for a command whose printed report is its only result when it writes no file
    /// (`files` false) and whose exit status tells nothing of that result: the work would be done for nothing.
    /// `hint` names what keeps a result, e.g. "give --csv FILE or --json".
    pub fn require_a_result(&self, files: bool, hint: &str) -> Result<()> {
        anyhow::ensure!(
            files || self.json || !self.quiet,
            "nothing to write: -q hides the report, this run's only result; {hint}"
        );
        Ok(())
    }

    /// Prints a line of human-readable text on stdout (not with `--json` or `--quiet`). When stdout cannot take it,
    /// the command ends there (its temporary files removed): quietly with status 141 when the reader went away
    /// (`tincull cull h.tch --eyes e.txt | head`), as a process ended by SIGPIPE, else with the error and status 1.
    pub fn say(&self, text: impl AsRef<str>) {
        if !self.quiet && !self.json && !self.quiet_text {
            let mut out = std::io::stdout().lock();
            if let Err(e) = writeln!(out, "{}", text.as_ref()).and_then(|_| out.flush()) {
                outfile::remove_temporaries();
                if e.kind() == std::io::ErrorKind::BrokenPipe {
                    std::process::exit(141);
                }
                let _ = writeln!(std::io::stderr(), "error: cannot write to standard output: {e}");
                std::process::exit(1);
            }
        }
    }

    /// Prints a warning on stderr, also with `--quiet` and `--json` (which keep stdout for the JSON). A stderr that
    /// cannot take it (closed: `tincull info m.obj 2>&1 >/dev/null | true`) is ignored: nobody is there to read it,
    /// and the command's work and status do not depend on it.
    pub fn warn(&self, text: impl AsRef<str>) {
        let _ = writeln!(std::io::stderr(), "warning: {}", text.as_ref());
    }

    /// Prints `value` as one JSON object on stdout when `--json` is set.
    pub fn json(&self, value: &serde_json::Value) -> Result<()> {
        if self.json {
            // Serialized first, so that a reader that went away is an I/O error (status 141 in `main`), not a
            // serialization one.
            let text = serde_json::to_string(value)?;
            let mut out = std::io::stdout().lock();
            writeln!(out, "{text}")?;
            out.flush()?;
        }
        Ok(())
    }

    /// A progress bar on stderr for `len` steps (hidden with `--quiet` or when stderr is not a terminal).
    pub fn progress(&self, len: u64, message: &str) -> ProgressBar {
        if self.quiet {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new(len);
        bar.set_style(
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(message.to_string());
        bar
    }

    /// A progress report for `bar` that never moves it backwards, for work whose threads report out of order
    /// (the horizon sweep's subsectors, the failure map's cells).
    pub fn monotone(bar: &ProgressBar) -> impl Fn(u64) + Send + Sync + 'static {
        let bar = bar.clone();
        let high = std::sync::Mutex::new(0u64);
        move |done: u64| {
            if let Ok(mut h) = high.lock()
                && done > *h
            {
                *h = done;
                bar.set_position(done);
            }
        }
    }

    /// A spinner on stderr for work of unknown length.
    pub fn spinner(&self, message: &str) -> ProgressBar {
        if self.quiet {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new_spinner();
        bar.set_message(message.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        bar
    }
}

/// A point for human text: `(x, y, z)` in metres to the millimetre (JSON output keeps every digit).
pub fn point(p: [f64; 3]) -> String {
    // To the millimetre; beyond 1e15 m (where f64 has no millimetres left) in scientific notation, not 300 digits.
    let c = |v: f64| {
        if v.abs() < 1e15 {
            format!("{v:.3}")
        } else {
            format!("{v:e}")
        }
    };
    format!("({}, {}, {})", c(p[0]), c(p[1]), c(p[2]))
}

/// `n` and `noun` (given in the singular) for human text, the noun in the plural unless `n` is 1: `count(1,
/// "range")` is "1 range", `count(3, "range")` "3 ranges", `count(2, "vertex")` "2 vertices". Not for JSON or CSV.
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        return format!("1 {noun}");
    }
    match noun {
        "vertex" => format!("{n} vertices"),
        "leaf" => format!("{n} leaves"),
        _ if noun.ends_with('s') || noun.ends_with('x') || noun.ends_with("ch") || noun.ends_with("sh") => {
            format!("{n} {noun}es")
        }
        _ => format!("{n} {noun}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::{count, point};

    #[test]
    fn points_are_printed_to_the_millimetre_and_huge_ones_briefly() {
        assert_eq!(point([1.0, -2.5, 1234.56789]), "(1.000, -2.500, 1234.568)");
        assert_eq!(point([1e300, 0.0, -2e15]), "(1e300, 0.000, -2e15)");
    }

    #[test]
    fn counts_agree_with_their_nouns() {
        assert_eq!(count(1, "range"), "1 range");
        assert_eq!(count(0, "range"), "0 ranges");
        assert_eq!(count(2, "vertex"), "2 vertices");
        assert_eq!(count(1, "vertex"), "1 vertex");
        assert_eq!(count(3, "leaf"), "3 leaves");
        assert_eq!(count(5, "pass"), "5 passes");
    }
}
