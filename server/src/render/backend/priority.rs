//! Scheduling priority of render threads.
#![allow(unsafe_code)] // one libc call, below

/// Lowers the calling thread's priority (nice +10). On Linux `setpriority`
/// with `PRIO_PROCESS` and id 0 acts on the calling thread alone. Failure
/// only means rendering competes evenly with everything else.
pub fn lower_current_thread() {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: setpriority takes plain integers and touches no memory.
        let rc = unsafe { libc::setpriority(libc::PRIO_PROCESS, 0, 10) };
        if rc != 0 {
            tracing::debug!("could not lower the render thread's priority");
        }
    }
}
