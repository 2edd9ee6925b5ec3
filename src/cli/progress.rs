//! The progress of `breed` on a terminal: a bar per generation with the
//! count of each class so far and the best score (indicatif).

use leafmagic::breed::population::OutcomeKind;
use leafmagic::breed::{self, GenerationSummary};
use leafmagic::physics::model::Model;
use leafmagic::physics::run::Work;

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

    fn individual_done(&self, outcome: OutcomeKind, score: f64) {
        use std::sync::atomic::Ordering::Relaxed;
        // Counted in OutcomeKind::ALL's order, as the bar's F S L U D.
        self.counts[outcome as usize].fetch_add(1, Relaxed);
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

/// The note a long run prints before it starts: "note: this {what} needs
/// about" the estimate, why its step is small, and the implicit
/// integrator's step count where it is fewer (`work` explained).
pub fn note(work: &Work, what: &str) -> String {
    let implicit = work.implicit_steps.map_or(String::new(), |n| {
        format!("; the implicit integrator would take {n:.0} steps")
    });
    let why = work.why();
    let why = if why.is_empty() {
        String::new()
    } else {
        format!(" ({why})")
    };
    format!(
        "note: this {what} needs about {}{why}{implicit}",
        work.describe()
    )
}

/// For a run whose estimated work is long ([`Work::is_long`]) but within
/// `limit`: a note on stderr with the estimate (and the implicit
/// integrator's step count where it is fewer), and a bar over its frames
/// on a terminal. `None` for a short run, or one that will be refused.
pub fn long_run(
    work: &Work,
    model: &Model,
    frame_dt: f64,
    what: &str,
    limit: f64,
) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !work.is_long() || work.particle_steps() > limit {
        return None;
    }
    eprintln!("{}", note(&work.clone().explained(model, frame_dt), what));
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let frames = work.frames as u64;
    let bar = indicatif::ProgressBar::new(frames);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{what} [{{bar:30}}] {{pos}}/{{len}} frames ({{elapsed}}, {{eta}} left)"
        ))
        .expect("valid template")
        .progress_chars("=> "),
    );
    Some(bar)
}
