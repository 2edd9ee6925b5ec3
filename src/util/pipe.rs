//! Standard output closed early by its reader.

/// `leafmagic ... | head` (or an example's) closes stdout early; `println!`
/// then panics with "failed printing to stdout: Broken pipe". That is the
/// reader's choice, not an error of ours: exit quietly (status 141, as a
/// shell reports a process ended by SIGPIPE) instead of printing a panic and
/// a backtrace. Files are written atomically ([`super::io::write_atomic`]),
/// so stopping here leaves nothing half-written. Call once, first thing in
/// `main`.
pub fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.contains("failed printing to stdout") && message.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}
