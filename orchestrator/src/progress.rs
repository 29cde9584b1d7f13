//! Progress of long work (`plamo run`, `plamo eval`, `plamo tune`): a bar on a
//! terminal, and where stderr is not one (a script, CI, a cluster job, whose logs
//! indicatif leaves empty) a line at every tenth of the work.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};

/// Lines logged over the whole work when stderr is not a terminal.
pub const LOG_LINES: u64 = 10;

/// A progress bar, or its log lines.
pub struct Progress {
    bar: ProgressBar,
    log: Option<Mutex<Log>>,
}

struct Log {
    what: String,
    len: u64,
    pos: u64,
    /// Tenths logged so far.
    logged: u64,
    message: String,
    start: Instant,
}

impl Progress {
    /// `len` units of work named `what` in the log lines; `template` is indicatif's
    /// for the bar; nothing at all when `quiet`.
    pub fn new(len: u64, what: &str, template: &str, quiet: bool) -> anyhow::Result<Self> {
        Self::with_terminal(len, what, template, quiet, std::io::stderr().is_terminal())
    }

    fn with_terminal(
        len: u64,
        what: &str,
        template: &str,
        quiet: bool,
        terminal: bool,
    ) -> anyhow::Result<Self> {
        if quiet {
            return Ok(Self {
                bar: ProgressBar::hidden(),
                log: None,
            });
        }
        let bar = ProgressBar::new(len);
        bar.set_style(ProgressStyle::with_template(template).context("progress template")?);
        let log = (!terminal).then(|| {
            Mutex::new(Log {
                what: what.into(),
                len,
                pos: 0,
                logged: 0,
                message: String::new(),
                start: Instant::now(),
            })
        });
        Ok(Self { bar, log })
    }

    /// `n` more units done (from any thread).
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.log_at(|pos| pos + n);
    }

    /// `pos` units done.
    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
        self.log_at(|_| pos);
    }

    /// The bar's message; log lines end with the latest one.
    pub fn set_message(&self, msg: String) {
        if let Some(log) = &self.log
            && let Ok(mut l) = log.lock()
        {
            l.message.clone_from(&msg);
        }
        self.bar.set_message(msg);
    }

    /// Done: the bar stays on screen.
    pub fn finish(&self) {
        self.bar.finish();
    }

    /// Done: the bar is removed.
    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }

    /// Stopped by an error: the bar stays where it was.
    pub fn abandon(&self) {
        self.bar.abandon();
    }

    /// Move the logged position; write a line when it enters a new tenth.
    fn log_at(&self, pos: impl FnOnce(u64) -> u64) {
        let Some(log) = &self.log else { return };
        let Ok(mut l) = log.lock() else { return };
        l.pos = pos(l.pos).min(l.len);
        let tenth = l.pos * LOG_LINES / l.len.max(1);
        if tenth > l.logged {
            l.logged = tenth;
            eprintln!("{}", l.line());
        }
    }
}

impl Log {
    fn line(&self) -> String {
        let mut s = format!(
            "{}: {}/{} ({:.0}%), {:.1} s",
            self.what,
            self.pos,
            self.len,
            100.0 * self.pos as f64 / self.len.max(1) as f64,
            self.start.elapsed().as_secs_f64()
        );
        if !self.message.is_empty() {
            s.push_str(": ");
            s.push_str(&self.message);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn logged(p: &Progress) -> u64 {
        p.log.as_ref().map_or(0, |l| l.lock().unwrap().logged)
    }

    /// Off a terminal, ten lines over the work, however it is counted; none when
    /// quiet or on a terminal (the bar draws there).
    #[test]
    fn logs_tenths_off_a_terminal() {
        let p = Progress::with_terminal(37, "runs", "{bar}", false, false).unwrap();
        for _ in 0..37 {
            p.inc(1);
        }
        assert_eq!(logged(&p), LOG_LINES);
        let p = Progress::with_terminal(1000, "run", "{bar}", false, false).unwrap();
        p.set_position(250);
        assert_eq!(logged(&p), 2);
        p.set_message("12.0 s simulated".into());
        assert!(
            p.log
                .as_ref()
                .unwrap()
                .lock()
                .unwrap()
                .line()
                .ends_with("12.0 s simulated")
        );
        p.set_position(5000);
        assert_eq!(logged(&p), LOG_LINES);
        for (quiet, terminal) in [(true, false), (false, true)] {
            let p = Progress::with_terminal(10, "x", "{bar}", quiet, terminal).unwrap();
            p.inc(10);
            assert_eq!(logged(&p), 0);
        }
    }
}
