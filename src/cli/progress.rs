//! The progress of `breed` on a terminal: a bar per generation with the
//! count of each class so far and the best score (indicatif).

use leafmagic::breed::{self, GenerationSummary};

/// A progress bar per generation on a terminal; nothing when piped.
pub struct Bar {
    bar: Option<indicatif::ProgressBar>,
    counts: [std::sync::atomic::AtomicUsize; 5],
    best: std::sync::Mutex<f64>,
}

impl Bar {
    /// A bar on stderr if it is a terminal, else none.
    pub fn new() -> Bar {
        use std::io::IsTerminal;
        Bar {
            bar: std::io::stderr()
                .is_terminal()
                .then(indicatif::ProgressBar::hidden),
            counts: Default::default(),
            best: std::sync::Mutex::new(f64::NEG_INFINITY),
        }
    }
}

impl breed::Progress for Bar {
    fn start_generation(&self, generation: usize, size: usize) {
        for c in &self.counts {
            c.store(0, std::sync::atomic::Ordering::Relaxed);
        }
        *self.best.lock().expect("progress lock") = f64::NEG_INFINITY;
        if let Some(bar) = &self.bar {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            bar.reset();
            bar.set_length(size as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "gen {prefix:>3} [{bar:30}] {pos}/{len} {msg} ({elapsed})",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            bar.set_prefix(generation.to_string());
        }
    }

    fn individual_done(&self, class: &str, score: f64) {
        use std::sync::atomic::Ordering::Relaxed;
        let k = ["floater", "spinner", "lilter", "undetermined", "diverged"]
            .iter()
            .position(|c| *c == class)
            .unwrap_or(3);
        self.counts[k].fetch_add(1, Relaxed);
        let best = {
            let mut b = self.best.lock().expect("progress lock");
            *b = b.max(score);
            *b
        };
        if let Some(bar) = &self.bar {
            let c: Vec<usize> = self.counts.iter().map(|c| c.load(Relaxed)).collect();
            bar.set_message(format!(
                "F{} S{} L{} U{} D{} best {best:.3}",
                c[0], c[1], c[2], c[3], c[4]
            ));
            bar.inc(1);
        }
    }

    fn finish_generation(&self, _: &GenerationSummary) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
