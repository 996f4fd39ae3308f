//! How many threads or worker processes a run may start. More than a few per core only queue
//! up behind each other, and a mistyped count (100000) would otherwise spawn until the machine
//! gives out; so every thread and worker count is refused above [`PER_CORE`] per core.

/// The most threads or worker processes per core a run starts.
pub const PER_CORE: usize = 4;

/// The cores this process may use (1 if the system cannot say).
pub fn available() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The most threads or worker processes a run starts on this machine.
pub fn max_parallel() -> usize {
    available() * PER_CORE
}

/// Checks a thread or worker count given by `flag`: at least 1, at most [`max_parallel`].
///
/// # Errors
/// The one line saying which bound `n` breaks.
pub fn check(flag: &str, n: usize) -> Result<(), String> {
    if n == 0 {
        return Err(format!("{flag}: {n} must be at least 1"));
    }
    let max = max_parallel();
    if n > max {
        return Err(format!(
            "{flag}: {n} is more than {max} ({PER_CORE} per core of this machine's {})",
            available()
        ));
    }
    Ok(())
}
