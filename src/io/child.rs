//! Worker child processes (campaign episodes, RL rollouts): a reply channel safe from stray
//! prints, and children that die with their parent.

use std::io::Write;
use std::process::Command;

/// The reply channel: a duplicate of the original stdout, with fd 1 itself pointed at stderr,
/// so that stray prints (SUMO's, a planner's `println!`) never mix into replies.
pub fn protocol_channel() -> std::io::Result<std::fs::File> {
    use std::os::fd::FromRawFd;
    std::io::stdout().flush()?;
    // SAFETY: plain fd calls; the duplicate is owned by the returned File alone.
    unsafe {
        let fd = libc::dup(1);
        if fd < 0 {
            return Err(std::io::Error::last_os_error());
        }
        if libc::dup2(2, 1) < 0 {
            let e = std::io::Error::last_os_error();
            libc::close(fd);
            return Err(e);
        }
        Ok(std::fs::File::from_raw_fd(fd))
    }
}

/// On Linux, the kernel kills the worker when its parent (a campaign, a trainer) dies, set up in the child before it
/// runs the binary, so there is no moment in which a killed parent can leave it orphaned (a
/// worker that asked for this itself, once started, could miss a parent killed in its first
/// milliseconds and then run its episode to the end). Elsewhere a worker ends when its stdin
/// closes.
pub fn die_with_parent(command: &mut Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        let parent = std::process::id() as libc::pid_t;
        // SAFETY: the closure runs in the forked child before exec and calls only prctl,
        // getppid and _exit, which are async-signal-safe.
        unsafe {
            command.pre_exec(move || {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                if libc::getppid() != parent {
                    libc::_exit(1);
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}
