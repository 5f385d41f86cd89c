//! Output files that never clobber what is not ours. Every crate of the workspace writes
//! its outputs through here.
//!
//! * A regular file is written under a temporary name beside its target
//!   (`.<name>.<pid>.<n>.tmp`) and renamed into place only when complete, so a failed or
//!   interrupted run never leaves a half-written file. The temporary file is removed on
//!   every error path, when dropped, and on SIGINT/SIGTERM (one handler, registered here).
//! * A symlink is followed: its target is written, the link stays.
//! * A target that exists and is not a regular file (`/dev/null`, `/dev/stdout`, a FIFO) is
//!   written through, never replaced; a directory is refused.
//! * An input of the run ([`Outputs::protect_input`]) is never an output (same device and
//!   inode).
//! * A staged run ([`Outputs::staged`], [`super::staging`]) that writes several files
//!   commits them together, all or none, also across concurrent runs and a kill during the
//!   commit.
//!
//! Every writer takes the run's [`Outputs`]: which files are staged and which inputs are
//! protected is the caller's explicit choice, never a process-wide switch, so runs in one
//! process (tests, a library caller) do not take in each other's outputs.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use super::live::{register, remove, unique, unregister};
use super::staging::{Stage, Staging};
use crate::error::Error;

/// Where a run's outputs go, handed to every writer: each file put in place as soon as it
/// is complete ([`Outputs::direct`]) or all of them together at [`Outputs::commit`]
/// ([`Outputs::staged`]), and never over one of the run's inputs.
#[derive(Debug)]
pub struct Outputs {
    /// The stage of a staged run.
    staging: Option<Staging>,
    /// Inputs of the run, as (device, inode, path).
    inputs: Vec<(u64, u64, PathBuf)>,
}

impl Outputs {
    /// Outputs put in place one by one, each when it is complete.
    pub fn direct() -> Outputs {
        Outputs {
            staging: None,
            inputs: Vec::new(),
        }
    }

    /// Outputs that wait in a stage until [`Outputs::commit`] puts them all in place;
    /// dropped uncommitted, none is left (see [`super::staging`]).
    pub fn staged() -> Outputs {
        Outputs {
            staging: Some(Staging::begin()),
            inputs: Vec::new(),
        }
    }

    /// Declares `path` an input of the run: no output may be it (nor, for a directory, one
    /// of the files in it).
    pub fn protect_input(&mut self, path: &Path) {
        let mut add = |p: &Path| {
            if let Ok(m) = std::fs::metadata(p) {
                self.inputs.push((m.dev(), m.ino(), p.to_path_buf()));
            }
        };
        add(path);
        if path.is_dir()
            && let Ok(rd) = std::fs::read_dir(path)
        {
            for e in rd.flatten() {
                add(&e.path());
            }
        }
    }

    /// Writes a whole file atomically with `fill`.
    pub fn write_atomic<F>(&self, target: &Path, fill: F) -> Result<(), Error>
    where
        F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
    {
        let mut f = AtomicFile::create(self, target)?;
        fill(f.writer()).map_err(|e| Error::io(target, e))?;
        f.commit()
    }

    /// Removes `path`, a regular file an earlier run left that this run does not write
    /// (never one of the run's inputs): in a staged run at the commit, with the run's
    /// outputs (a failed run removes nothing); in a direct run now. A path that is missing
    /// or not a regular file is left alone.
    pub fn remove_at_commit(&self, path: &Path) -> Result<(), Error> {
        let is_file = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file());
        if !is_file {
            return Ok(());
        }
        check_not_input(self, path, path)?;
        if let Some(stage) = self.stage()
            && super::staging::remove_at_commit(stage, path)
        {
            return Ok(());
        }
        std::fs::remove_file(path).map_err(|e| Error::io(path, e))
    }

    /// Makes sure the output directory `dir` can take outputs: in a staged run nothing is
    /// created (its commit makes the directory, so a failed run leaves none); otherwise the
    /// directory and its parents are created.
    pub fn ensure_dir(&self, dir: &Path) -> Result<(), Error> {
        if let Some(stage) = self.stage()
            && super::staging::may_create(stage, dir)
        {
            return Ok(());
        }
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
    }

    /// Puts a staged run's outputs in place (a direct run's are already). If that fails,
    /// what was not yet in place is removed and the error names the first failure.
    pub fn commit(self) -> Result<(), Error> {
        match self.staging {
            Some(s) => s.commit(),
            None => Ok(()),
        }
    }

    fn stage(&self) -> Option<&Stage> {
        self.staging.as_ref().map(Staging::stage)
    }
}

// The OS-error wording lives with the error type (error.rs), which every crate's `Io`
// variant formats with; re-exported here where callers have always found it.
pub use crate::error::describe;
pub(crate) use crate::error::without_errno;

/// Symlinks followed at most (the kernel's limit, `MAXSYMLINKS`).
const MAX_SYMLINKS: usize = 40;

/// The file a path names once its symlinks are followed (a dangling link names its target);
/// a loop of links (or a longer chain than the kernel follows) is refused.
fn resolve(target: &Path) -> Result<PathBuf, Error> {
    let mut p = target.to_path_buf();
    for _ in 0..MAX_SYMLINKS {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::read_link(&p) {
                Ok(to) if to.is_absolute() => p = to,
                Ok(to) => {
                    p = p.parent().map(|d| d.join(&to)).unwrap_or(to);
                }
                Err(_) => return Ok(p),
            },
            _ => return Ok(p),
        }
    }
    Err(Error::Output {
        path: target.to_path_buf(),
        what: "it is a loop of symbolic links (or a chain of more than 40)".into(),
    })
}

/// Refuses an output that is an input of the run.
fn check_not_input(outputs: &Outputs, target: &Path, real: &Path) -> Result<(), Error> {
    let Ok(m) = std::fs::metadata(real) else {
        return Ok(());
    };
    for (dev, ino, input) in outputs.inputs.iter() {
        if m.dev() == *dev && m.ino() == *ino {
            return Err(Error::Output {
                path: target.to_path_buf(),
                what: format!(
                    "it is the input {} (choose another output; the input is never overwritten)",
                    input.display()
                ),
            });
        }
    }
    Ok(())
}

/// A temporary path for a file that is renamed into place on commit (or, in a staged run,
/// written in its stage), and removed otherwise.
pub struct TempPath {
    tmp: PathBuf,
    target: PathBuf,
    done: bool,
    /// A file (staged with its directory), not a directory.
    file: bool,
    /// The stage of a staged run, where the commit hands the path.
    stage: Option<Stage>,
}

impl TempPath {
    /// Where to write `target` (after its symlinks) until it is committed: a fresh
    /// `.<name>.<pid>.<n><suffix>` beside it, or its place in a staged run's stage;
    /// registered for removal on SIGINT/SIGTERM. Nothing is created but a stage.
    pub fn beside(outputs: &Outputs, target: &Path, suffix: &str) -> Result<TempPath, Error> {
        let real = resolve(target)?;
        check_not_input(outputs, target, &real)?;
        if real.is_dir() {
            return Err(Error::Output {
                path: target.to_path_buf(),
                what: "it is a directory (name a file)".into(),
            });
        }
        if let Some(stage) = outputs.stage()
            && let Some(tmp) = super::staging::file_path(stage, &real)?
        {
            return Ok(TempPath {
                tmp,
                target: real,
                done: false,
                file: true,
                stage: Some(stage.clone()),
            });
        }
        let mut t = Self::beside_path(outputs, target, &real, suffix)?;
        t.file = true;
        Ok(t)
    }

    /// A fresh temporary name beside `target` for a directory.
    fn beside_dir(outputs: &Outputs, target: &Path) -> Result<TempPath, Error> {
        let real = resolve(target)?;
        check_not_input(outputs, target, &real)?;
        Self::beside_path(outputs, target, &real, ".tmp")
    }

    fn beside_path(
        outputs: &Outputs,
        target: &Path,
        real: &Path,
        suffix: &str,
    ) -> Result<TempPath, Error> {
        if real.is_dir() {
            return Err(Error::Output {
                path: target.to_path_buf(),
                what: "it is a directory (name a file)".into(),
            });
        }
        let dir = match real.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = real.file_name().ok_or_else(|| Error::Output {
            path: target.to_path_buf(),
            what: "the path has no file name".into(),
        })?;
        let tmp = dir.join(unique(&name.to_string_lossy(), suffix));
        register(&tmp);
        Ok(TempPath {
            tmp,
            target: real.to_path_buf(),
            done: false,
            file: false,
            stage: outputs.stage().cloned(),
        })
    }

    /// Where to write now.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Renames the temporary path into place, or hands it to its run's stage. On failure
    /// the temporary path is removed and the error names the target.
    pub fn commit(mut self) -> Result<(), Error> {
        self.done = true;
        if let Some(stage) = &self.stage
            && super::staging::record(stage, &self.tmp, &self.target, self.file)
        {
            return Ok(());
        }
        let r = std::fs::rename(&self.tmp, &self.target);
        if r.is_err() {
            remove(&self.tmp);
        }
        unregister(&self.tmp);
        r.map_err(|e| Error::io(&self.target, e))
    }
}

impl Drop for TempPath {
    fn drop(&mut self) {
        if !self.done {
            remove(&self.tmp);
            unregister(&self.tmp);
        }
    }
}

/// Where an [`AtomicFile`] writes.
enum Dest {
    /// A temporary file renamed into place on commit.
    Temp(TempPath),
    /// An existing non-regular file (device, FIFO), written directly.
    Through,
}

/// A file being written; [`AtomicFile::commit`] puts it in place. Dropped without a commit,
/// nothing is left behind.
pub struct AtomicFile {
    dest: Dest,
    target: PathBuf,
    file: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Starts writing `target` (see the module doc for symlinks, devices and inputs).
    pub fn create(outputs: &Outputs, target: &Path) -> Result<AtomicFile, Error> {
        check_not_input(outputs, target, target)?;
        // Devices and FIFOs (also behind /dev/stdout's links into /proc) are opened as named.
        let through = std::fs::metadata(target)
            .map(|m| !m.is_file() && !m.is_dir())
            .unwrap_or(false);
        let (dest, file) = if through {
            let f = std::fs::OpenOptions::new()
                .write(true)
                .truncate(true)
                .open(target)
                .map_err(|e| Error::io(target, e))?;
            (Dest::Through, f)
        } else {
            let t = TempPath::beside(outputs, target, ".tmp")?;
            let f = File::create(t.path()).map_err(|e| Error::io(target, e))?;
            (Dest::Temp(t), f)
        };
        Ok(AtomicFile {
            dest,
            target: target.to_path_buf(),
            file: Some(BufWriter::with_capacity(1 << 20, file)),
        })
    }

    /// The writer (buffered).
    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.file.as_mut().expect("AtomicFile used after commit")
    }

    /// The final path, as given.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Flushes and puts the file in place. The rename is atomic: readers see the old file or
    /// the whole new one. There is no fsync: the guarantee is against failed or interrupted
    /// runs, not power loss, and an fsync of a 1 GB bag would double its cost. On any error
    /// the temporary file is removed.
    pub fn commit(mut self) -> Result<(), Error> {
        let file = self.file.take().expect("AtomicFile committed twice");
        let flushed = file
            .into_inner()
            .map_err(|e| Error::io(&self.target, e.into_error()));
        drop(flushed?);
        match std::mem::replace(&mut self.dest, Dest::Through) {
            Dest::Temp(t) => t.commit(),
            Dest::Through => Ok(()),
        }
    }
}

/// A directory being filled under a temporary name beside the target; [`AtomicDir::commit`]
/// renames it into place. Dropped without a commit, it is removed with everything in it.
/// The target must not exist (a bag directory is never merged into or replaced, as
/// `ros2 bag record` refuses an existing one).
pub struct AtomicDir {
    tmp: TempPath,
    target: PathBuf,
}

impl AtomicDir {
    /// Creates the temporary directory; fails when `target` already exists.
    pub fn create(outputs: &Outputs, target: &Path) -> Result<AtomicDir, Error> {
        if target.exists() {
            return Err(Error::Output {
                path: target.to_path_buf(),
                what: "it already exists (remove it or choose another output)".into(),
            });
        }
        let tmp = TempPath::beside_dir(outputs, target)?;
        std::fs::create_dir(tmp.path()).map_err(|e| Error::io(target, e))?;
        Ok(AtomicDir {
            tmp,
            target: target.to_path_buf(),
        })
    }

    /// Where to write the files now.
    pub fn path(&self) -> &Path {
        self.tmp.path()
    }

    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the directory into place.
    pub fn commit(self) -> Result<(), Error> {
        self.tmp.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn failed_write_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.txt");
        let out = Outputs::direct();
        let r = out.write_atomic(&target, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert!(names(dir.path()).is_empty());
        out.write_atomic(&target, |w| w.write_all(b"whole"))
            .unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"whole");
        assert_eq!(names(dir.path()), vec!["out.txt"]);
    }

    #[test]
    fn symlinks_are_followed_and_devices_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.txt");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink("real.txt", &link).unwrap();
        let out = Outputs::direct();
        out.write_atomic(&link, |w| w.write_all(b"new")).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        out.write_atomic(Path::new("/dev/null"), |w| w.write_all(b"x"))
            .unwrap();
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
    }

    #[test]
    fn staging_commits_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        {
            let out = Outputs::staged();
            out.write_atomic(&a, |w| w.write_all(b"a")).unwrap();
            out.write_atomic(&b, |w| w.write_all(b"b")).unwrap();
            assert!(!a.exists() && !b.exists());
        }
        assert!(names(dir.path()).is_empty(), "dropped staging left files");
        let out = Outputs::staged();
        out.write_atomic(&a, |w| w.write_all(b"a")).unwrap();
        out.write_atomic(&b, |w| w.write_all(b"b")).unwrap();
        out.commit().unwrap();
        assert_eq!(names(dir.path()), vec!["a", "b"]);
    }

    /// An earlier run's file this run retires goes at the commit, with the new files, and
    /// stays when the run fails (its stage dropped).
    #[test]
    fn a_retired_file_goes_with_the_commit_and_only_then() {
        let dir = tempfile::tempdir().unwrap();
        let (a, old) = (dir.path().join("a"), dir.path().join("old"));
        std::fs::write(&a, b"a0").unwrap();
        std::fs::write(&old, b"old").unwrap();
        {
            let out = Outputs::staged();
            out.write_atomic(&a, |w| w.write_all(b"a1")).unwrap();
            out.remove_at_commit(&old).unwrap();
            assert!(old.exists());
        }
        assert_eq!(
            names(dir.path()),
            vec!["a", "old"],
            "a failed run removed a file"
        );
        assert_eq!(std::fs::read(&a).unwrap(), b"a0");
        // the whole directory is replaced (the exchange) or filled (the moves): both paths
        for extra in [false, true] {
            std::fs::write(&old, b"old").unwrap();
            if extra {
                // a file of the user's: the directory cannot be exchanged whole
                std::fs::write(dir.path().join("mine"), b"x").unwrap();
            }
            let out = Outputs::staged();
            out.write_atomic(&a, |w| w.write_all(b"a2")).unwrap();
            out.remove_at_commit(&old).unwrap();
            out.commit().unwrap();
            let mut want = vec!["a"];
            if extra {
                want.push("mine");
            }
            assert_eq!(names(dir.path()), want);
            assert_eq!(std::fs::read(&a).unwrap(), b"a2");
        }
        // in a directory the run writes nothing into, and never an input
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(sub.join("old"), b"old").unwrap();
        std::fs::write(sub.join("input"), b"in").unwrap();
        let mut out = Outputs::staged();
        out.protect_input(&sub.join("input"));
        assert!(out.remove_at_commit(&sub.join("input")).is_err());
        out.remove_at_commit(&sub.join("old")).unwrap();
        out.commit().unwrap();
        assert_eq!(names(&sub), vec!["input"]);
    }
}
