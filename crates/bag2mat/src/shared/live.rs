//! The temporary paths alive in this process (outputs being written, stages): registered
//! while they exist, removed on SIGINT/SIGTERM (one handler) and after a failed allocation.
//! Below both the atomic outputs ([`super::output`]) and the staging ([`super::staging`]),
//! which create such paths.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Temporary paths alive in this process (files or directories), removed on SIGINT/SIGTERM.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Makes temporary names unique within the process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

pub(super) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Installs, once, the SIGINT/SIGTERM handler that removes every live temporary path and
/// then exits with the conventional status (130, 143).
fn install_signal_cleanup() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
            return;
        };
        // Without the thread (no memory left to start one) only the cleanup on signals is lost.
        let _ = std::thread::Builder::new().spawn(move || {
            if let Some(sig) = signals.forever().next() {
                for p in lock(&LIVE).drain(..) {
                    remove(&p);
                }
                std::process::exit(128 + sig);
            }
        });
    });
}

/// Removes every live temporary path, after a failed allocation ([`super::alloc`]): the
/// lock is only tried (the failing thread may hold it).
pub(super) fn remove_live_paths() {
    if let Ok(mut v) = LIVE.try_lock() {
        for p in v.drain(..) {
            remove(&p);
        }
    }
}

pub(super) fn register(p: &Path) {
    install_signal_cleanup();
    lock(&LIVE).push(p.to_path_buf());
}

pub(super) fn unregister(p: &Path) {
    lock(&LIVE).retain(|x| x != p);
}

/// A fresh name `.<name>.<pid>.<n><suffix>` (unique in the process).
pub(super) fn unique(name: &str, suffix: &str) -> String {
    format!(
        ".{name}.{}.{}{suffix}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )
}

pub(super) fn remove(p: &Path) {
    if p.is_dir() {
        let _ = std::fs::remove_dir_all(p);
    } else {
        let _ = std::fs::remove_file(p);
    }
}
