//! A log file's bytes in memory, mapped rather than copied: the text and ULog readers walk
//! the whole file (several hundred MB for hours of 200 Hz data) and a copy through `read`
//! cost them as much as the parsing (issue 20's benchmarks).
//!
//! A mapping reads what the file holds while it is read: a log that another program
//! rewrites meanwhile gives what it then holds, as `read` would; one it shortens meanwhile
//! ends the process (SIGBUS), a risk every mapping reader (ripgrep, git) takes for speed.

use std::fs::File;
use std::path::Path;

use crate::error::Error;

/// Mappings of at least this many bytes are unmapped on a helper thread (Linux): tearing
/// down the page tables of a 400 MB log took about 14 ms, a tenth of reading it (issue 20's
/// benchmark), and the reader need not wait for it.
const UNMAP_AWAY_BYTES: usize = 64 << 20;

/// A file's bytes, read only.
pub struct Mapped {
    map: Option<memmap2::Mmap>,
}

impl Mapped {
    /// Maps `file` (at `path`, for messages); an empty file is an empty slice.
    pub(crate) fn of(file: &File, path: &Path) -> Result<Mapped, Error> {
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        if len == 0 {
            return Ok(Mapped { map: None });
        }
        // SAFETY: the mapping is read only and only read as plain bytes. Rust assumes the
        // slice does not change while borrowed: a file rewritten or cut under the reader
        // breaks that, the risk the module doc states and every mapping reader takes.
        let map =
            unsafe { memmap2::MmapOptions::new().map(file) }.map_err(|e| Error::io(path, e))?;
        Ok(Mapped { map: Some(map) })
    }

    /// True when a file of `len` bytes may be mapped whole: it takes under half the address
    /// space a memory limit (`RLIMIT_AS`) leaves, so that the rows read from it fit too. A
    /// reader that can read a file in windows does so otherwise.
    pub(crate) fn fits(len: u64) -> bool {
        #[cfg(unix)]
        {
            let mut lim = libc::rlimit {
                rlim_cur: 0,
                rlim_max: 0,
            };
            // SAFETY: getrlimit writes the struct it is given, which lives on this stack.
            let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) } == 0;
            if ok && lim.rlim_cur != libc::RLIM_INFINITY {
                // rlim_t is u64 on Linux, another width on some other unixes
                #[allow(clippy::unnecessary_cast)]
                let cur = lim.rlim_cur as u64;
                return len < cur / 2;
            }
        }
        true
    }

    /// Fills the mapping's page tables from the page cache, in file order (Linux
    /// `MADV_POPULATE_READ`; elsewhere, or on a kernel without it, nothing). Run beside a
    /// one-threaded first pass over the file (the ULog hop), it takes the page faults off that
    /// pass: about a tenth of the hop's time. Advice only: a failure changes nothing.
    pub(crate) fn fill_pages(&self) {
        #[cfg(target_os = "linux")]
        if let Some(m) = &self.map {
            let _ = m.advise(memmap2::Advice::PopulateRead);
        }
    }

    /// The bytes.
    pub(crate) fn bytes(&self) -> &[u8] {
        self.map.as_deref().unwrap_or(&[])
    }
}

impl Drop for Mapped {
    fn drop(&mut self) {
        // Linux only: elsewhere a file cannot always be removed while mapped, and a caller
        // that removes the log right after reading it must be able to
        #[cfg(target_os = "linux")]
        if let Some(m) = self.map.take().filter(|m| m.len() >= UNMAP_AWAY_BYTES) {
            // a thread that cannot start drops the mapping here, with the closure
            let _ = std::thread::Builder::new()
                .name("unmap".into())
                .spawn(move || drop(m));
        }
    }
}
