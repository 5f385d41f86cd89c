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

/// The page size the prefault offsets are aligned to (4 KiB on every target we build for;
/// a larger page only makes the hint fail, never the read).
const PAGE_BYTES: usize = 4096;
/// Bytes prefaulted by one call of [`Mapped::prefault_all`]'s workers.
const PREFAULT_CHUNK: usize = 8 << 20;
/// Populate the page tables readable (Linux 5.14+); elsewhere a plain will-need hint.
#[cfg(target_os = "linux")]
const PREFAULT: memmap2::Advice = memmap2::Advice::PopulateRead;
#[cfg(all(unix, not(target_os = "linux")))]
const PREFAULT: memmap2::Advice = memmap2::Advice::WillNeed;

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

    /// The bytes.
    pub(crate) fn bytes(&self) -> &[u8] {
        self.map.as_deref().unwrap_or(&[])
    }

    /// Maps in bytes `start..end` ahead of reading them, in one call rather than a page
    /// fault every few pages (the readers' workers each prefault the range they walk: a
    /// third of a ULog read went to faults). Only a hint: where the kernel refuses it, the
    /// pages fault in as they are read.
    pub(crate) fn prefault(&self, start: usize, end: usize) {
        #[cfg(unix)]
        self.advise(start, end);
        #[cfg(not(unix))]
        let _ = (start, end);
    }

    /// [`Mapped::prefault`] of the whole file, in chunks on every worker.
    pub(crate) fn prefault_all(&self) {
        use rayon::prelude::*;
        let len = self.bytes().len();
        let starts: Vec<usize> = (0..len).step_by(PREFAULT_CHUNK).collect();
        starts
            .par_iter()
            .for_each(|&a| self.prefault(a, a + PREFAULT_CHUNK));
    }

    #[cfg(unix)]
    fn advise(&self, start: usize, end: usize) {
        let Some(map) = &self.map else { return };
        let end = end.min(map.len());
        if start >= end {
            return;
        }
        // advise_range wants a page-aligned offset
        let page = PAGE_BYTES;
        let a = start / page * page;
        let _ = map.advise_range(PREFAULT, a, end - a);
    }
}
