//! Several outputs committed together, all or none — also across concurrent runs into one
//! directory and a kill during the commit.
//!
//! Every file the atomic outputs of [`super::output`] write through a staged
//! [`super::output::Outputs`] (which holds a `Staging`) waits in a stage:
//!
//! * for a directory that does not exist yet: a hidden directory beside it
//!   (`.<name>.<pid>.<n>.tmp`) that one rename turns into it;
//! * for an existing directory: the same hidden directory beside it, exchanged with it in
//!   one step (`renameat2(RENAME_EXCHANGE)`) when the directory holds nothing but files this
//!   run replaces; otherwise its files are moved in one by one, after a journal (a `.commit`
//!   file in the stage) that lets the next run finish a commit a kill interrupted;
//! * for the current directory (or one beside which no stage can be made): hidden temporary
//!   files inside it, moved in the same way after a journal.
//!
//! A run may also retire files of an earlier run
//! ([`super::output::Outputs::remove_at_commit`]): they are removed
//! by the same commit (with the exchange, as the old directory goes; after the moves, named
//! in the journal so that the next run finishes a killed commit's removals too), and not at
//! all if the run fails.
//!
//! A commit holds an advisory lock (`flock`) on the directory that holds the stage, so
//! concurrent runs commit one after the other and the directory ends with one run's
//! complete set. Before committing, a run finishes the journaled commits of runs that are
//! gone (their pid no longer exists) and removes their other leftovers there.
//!
//! `BAG2MAT_TEST_COMMIT_DELAY_MS` (a test hook) slows each step of a commit, as a slow or
//! network file system would, and says so on stderr, for the tests of concurrent and killed
//! runs.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::live::{lock, register, remove, unique, unregister};
use crate::error::Error;

/// The name of the journal a stage holds while its files are moved in one by one.
const JOURNAL: &str = ".commit";
/// The suffix of a journal beside temporary files inside an output directory.
const JOURNAL_SUFFIX: &str = ".commit";

/// Where one output directory's files wait for the commit.
#[derive(Debug)]
struct Area {
    /// The output directory (canonical when it existed).
    dir: PathBuf,
    /// What the stage stands for: `dir`, or its first ancestor that did not exist.
    root: PathBuf,
    /// The stage directory beside `root`; `None`: hidden temporary files inside `dir`.
    stage: Option<PathBuf>,
    /// Staged files: (temporary path, target).
    files: Vec<(PathBuf, PathBuf)>,
}

impl Area {
    /// Where `dir` is inside the stage.
    fn staged_dir(&self) -> Option<PathBuf> {
        let s = self.stage.as_ref()?;
        Some(match self.dir.strip_prefix(&self.root) {
            Ok(rel) if !rel.as_os_str().is_empty() => s.join(rel),
            _ => s.clone(),
        })
    }
}

/// What an active [`Staging`] holds.
#[derive(Debug, Default)]
struct Staged {
    areas: Vec<Area>,
    /// Other temporary paths (directories) renamed into place at the commit.
    pairs: Vec<(PathBuf, PathBuf)>,
    /// Output directories the run may create (the commit makes them).
    creatable: Vec<PathBuf>,
    /// Files of an earlier run to remove at the commit (canonical directory, file name).
    removals: Vec<(PathBuf, std::ffi::OsString)>,
}

/// A run's stage, shared by its [`Staging`] and the temporary paths written in it (which
/// record themselves at their commit); empty once the staging is committed or dropped.
#[derive(Clone, Debug)]
pub(super) struct Stage(Arc<Mutex<Option<Staged>>>);

/// Declares `dir` an output directory the stage's commit may create; false once the
/// stage is gone.
pub(super) fn may_create(stage: &Stage, dir: &Path) -> bool {
    match lock(&stage.0).as_mut() {
        Some(s) => {
            s.creatable.push(dir.to_path_buf());
            true
        }
        None => false,
    }
}

/// The temporary path a staged file for `target` (a resolved path, not a directory) is
/// written at: in its directory's stage, created on first use. `None` once the stage is
/// gone.
pub(super) fn file_path(stage: &Stage, target: &Path) -> Result<Option<PathBuf>, Error> {
    let mut g = lock(&stage.0);
    let Some(staged) = g.as_mut() else {
        return Ok(None);
    };
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = target.file_name().ok_or_else(|| Error::Output {
        path: target.to_path_buf(),
        what: "the path has no file name".into(),
    })?;
    let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
    let k = match staged.areas.iter().position(|a| a.dir == dir) {
        Some(k) => k,
        None => {
            if dir.exists() && !dir.is_dir() {
                return Err(Error::io(
                    target,
                    std::io::Error::from(std::io::ErrorKind::NotADirectory),
                ));
            }
            if !dir.exists() && !staged.creatable.iter().any(|c| dir.starts_with(c)) {
                // Only a declared output directory is made; another is missing.
                return Err(Error::io(
                    target,
                    std::io::Error::from(std::io::ErrorKind::NotFound),
                ));
            }
            let area = new_area(&dir)?;
            staged.areas.push(area);
            staged.areas.len() - 1
        }
    };
    let area = &staged.areas[k];
    Ok(Some(match area.staged_dir() {
        Some(d) => d.join(name),
        None => {
            let t = area.dir.join(unique(&name.to_string_lossy(), ".tmp"));
            register(&t);
            t
        }
    }))
}

/// Declares `path` (a regular file that is not an output of this run) to be removed at the
/// commit; false once the stage is gone.
pub(super) fn remove_at_commit(stage: &Stage, path: &Path) -> bool {
    let mut g = lock(&stage.0);
    let Some(staged) = g.as_mut() else {
        return false;
    };
    let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else {
        return true;
    };
    let dir = if dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        dir.to_path_buf()
    };
    let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
    if !staged.removals.iter().any(|(d, n)| *d == dir && n == name) {
        staged.removals.push((dir, name.to_os_string()));
    }
    true
}

/// Records a committed staged file (`tmp` → `target`), or another temporary path to rename
/// at the commit. Returns false once the stage is gone.
pub(super) fn record(stage: &Stage, tmp: &Path, target: &Path, file: bool) -> bool {
    let mut g = lock(&stage.0);
    let Some(staged) = g.as_mut() else {
        return false;
    };
    if file {
        for a in staged.areas.iter_mut() {
            let inside = match a.staged_dir() {
                Some(d) => tmp.parent() == Some(d.as_path()),
                None => tmp.parent() == Some(a.dir.as_path()),
            };
            if inside {
                a.files.retain(|f| f.1 != target);
                a.files.push((tmp.to_path_buf(), target.to_path_buf()));
                return true;
            }
        }
    }
    staged.pairs.push((tmp.to_path_buf(), target.to_path_buf()));
    true
}

/// The stage of output directory `dir`: a new hidden directory beside it (or beside its
/// first missing ancestor), else temporary files inside it.
fn new_area(dir: &Path) -> Result<Area, Error> {
    // The first missing ancestor is what the stage becomes.
    let mut root = dir.to_path_buf();
    while let Some(p) = root.parent() {
        if p.as_os_str().is_empty() || p.exists() {
            break;
        }
        root = p.to_path_buf();
    }
    let exists = dir.exists();
    let cwd = std::env::current_dir().ok();
    let beside = root
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map(Path::to_path_buf)
        .or_else(|| (!exists).then(|| PathBuf::from(".")));
    let name = root.file_name().map(|n| n.to_string_lossy().into_owned());
    let stage = match (beside, name) {
        (Some(b), Some(n)) if !(exists && cwd.as_deref() == Some(dir)) => {
            let s = b.join(unique(&n, ".tmp"));
            let staged_dir = match dir.strip_prefix(&root) {
                Ok(rel) if !rel.as_os_str().is_empty() => s.join(rel),
                _ => s.clone(),
            };
            match std::fs::create_dir_all(&staged_dir) {
                Ok(()) => {
                    register(&s);
                    Some(s)
                }
                Err(e) if !exists => return Err(Error::io(dir, e)),
                // A parent that takes no stage: temporary files inside the directory.
                Err(_) => {
                    let _ = std::fs::remove_dir_all(&s);
                    None
                }
            }
        }
        _ if exists => None,
        _ => {
            return Err(Error::Output {
                path: dir.to_path_buf(),
                what: "no directory to stage the outputs beside".into(),
            });
        }
    };
    Ok(Area {
        dir: dir.to_path_buf(),
        root,
        stage,
        files: Vec::new(),
    })
}

/// Sleeps as long as `BAG2MAT_TEST_COMMIT_DELAY_MS` says (a test hook: a slow rename).
fn test_delay() {
    static MS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    let ms = *MS.get_or_init(|| {
        std::env::var("BAG2MAT_TEST_COMMIT_DELAY_MS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    });
    if ms > 0 {
        // The tests kill a run at this line.
        eprintln!("bag2mat test hook: commit step");
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// An exclusive advisory lock on a directory, held until dropped.
struct DirLock(Option<std::fs::File>);

impl DirLock {
    fn take(dir: &Path) -> DirLock {
        match std::fs::File::open(dir) {
            Ok(f) if f.lock().is_ok() => DirLock(Some(f)),
            // A file system without locks: the commit still runs, unserialised.
            _ => DirLock(None),
        }
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        if let Some(f) = &self.0 {
            let _ = f.unlock();
        }
    }
}

/// The pid in a name `.<name>.<pid>.<n><suffix>` this module and [`super::output`] give
/// temporary paths.
fn pid_of(name: &str, suffix: &str) -> Option<u32> {
    let s = name.strip_prefix('.')?.strip_suffix(suffix)?;
    let mut it = s.rsplitn(3, '.');
    let _n: u64 = it.next()?.parse().ok()?;
    let pid: u32 = it.next()?.parse().ok()?;
    it.next()?;
    Some(pid)
}

fn alive(pid: u32) -> bool {
    pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
}

/// Finishes the journaled commits that dead runs left in `dir` and removes their other
/// temporary paths.
fn recover(dir: &Path) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let names: Vec<OsString> = rd.flatten().map(|e| e.file_name()).collect();
    // Journals first: their temporary files are the commit to finish.
    for n in &names {
        let s = n.to_string_lossy();
        if let Some(pid) = pid_of(&s, JOURNAL_SUFFIX)
            && !alive(pid)
        {
            let j = dir.join(n);
            if let Ok(text) = std::fs::read_to_string(&j) {
                for line in text.lines() {
                    match line.split_once('\t') {
                        // a removal of an earlier run's file
                        Some(("", target)) => {
                            let _ = std::fs::remove_file(dir.join(target));
                        }
                        Some((tmp, target)) => {
                            let _ = std::fs::rename(dir.join(tmp), dir.join(target));
                        }
                        None => {}
                    }
                }
            }
            let _ = std::fs::remove_file(&j);
        }
    }
    for n in &names {
        let s = n.to_string_lossy();
        let Some(pid) = pid_of(&s, ".tmp").or_else(|| pid_of(&s, ".tmp.png")) else {
            continue;
        };
        if alive(pid) {
            continue;
        }
        let p = dir.join(n);
        // A stage whose journal says its commit began: move what is left into place.
        if p.join(JOURNAL).exists()
            && let Some(real) = s
                .strip_prefix('.')
                .and_then(|x| x.strip_suffix(".tmp"))
                .and_then(|x| x.rsplitn(3, '.').nth(2))
        {
            let target = dir.join(real);
            let removals = std::fs::read_to_string(p.join(JOURNAL)).unwrap_or_default();
            let _ = move_into(&p, &target, &mut |_| Ok(()));
            for name in removals.lines().filter(|l| !l.is_empty()) {
                let _ = std::fs::remove_file(target.join(name));
            }
        }
        remove(&p);
    }
}

/// Moves every file under `from` to the same place under `to` (creating directories),
/// calling `step` before each rename.
fn move_into(
    from: &Path,
    to: &Path,
    step: &mut dyn FnMut(&Path) -> std::io::Result<()>,
) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        if e.file_name() == JOURNAL {
            continue;
        }
        let src = e.path();
        let dst = to.join(e.file_name());
        if e.file_type()?.is_dir() && dst.is_dir() {
            move_into(&src, &dst, step)?;
        } else {
            step(&dst)?;
            std::fs::rename(&src, &dst)?;
        }
    }
    Ok(())
}

/// True when every entry of `dir` is a file this commit replaces or a temporary path of
/// these tools: the directory can be exchanged whole.
fn only_replaced(dir: &Path, replaced: &[&std::ffi::OsStr]) -> bool {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return false;
    };
    rd.flatten().all(|e| {
        let n = e.file_name();
        let s = n.to_string_lossy();
        let file = e.file_type().is_ok_and(|t| t.is_file());
        (file && replaced.contains(&n.as_os_str()))
            || pid_of(&s, ".tmp").is_some()
            || pid_of(&s, JOURNAL_SUFFIX).is_some()
    })
}

/// Exchanges two directories in one step.
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let ca = std::ffi::CString::new(a.as_os_str().as_bytes())?;
    let cb = std::ffi::CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: two NUL-terminated paths; renameat2 only reads them.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// Commits one area: one rename or exchange when it can, else the journaled moves; the
/// `removals` (file names in the area's directory) go with it.
fn commit_area(a: &Area, removals: &[std::ffi::OsString]) -> Result<(), Error> {
    let holder = a
        .stage
        .as_ref()
        .and_then(|s| s.parent())
        .map(Path::to_path_buf)
        .unwrap_or_else(|| a.dir.clone());
    let _lock = DirLock::take(&holder);
    recover(&holder);
    if holder != a.dir {
        recover(&a.dir);
    }
    test_delay();
    let Some(stage) = &a.stage else {
        return commit_in_place(a, removals);
    };
    // A directory that did not exist becomes the stage.
    if !a.root.exists() {
        match std::fs::rename(stage, &a.root) {
            Ok(()) => {
                unregister(stage);
                return Ok(());
            }
            // Another run made it meanwhile: commit into it.
            Err(_) if a.root.is_dir() => {}
            Err(e) => return Err(Error::io(&a.root, e)),
        }
    }
    let mut names: Vec<&std::ffi::OsStr> = a.files.iter().filter_map(|f| f.1.file_name()).collect();
    names.extend(removals.iter().map(|n| n.as_os_str()));
    let same_owner = |p: &Path| {
        use std::os::unix::fs::MetadataExt;
        // SAFETY: geteuid has no preconditions.
        std::fs::metadata(p).is_ok_and(|m| m.uid() == unsafe { libc::geteuid() })
    };
    if a.root == a.dir && only_replaced(&a.dir, &names) && same_owner(&a.dir) {
        if let Ok(m) = std::fs::metadata(&a.dir) {
            let _ = std::fs::set_permissions(stage, m.permissions());
        }
        if exchange(stage, &a.dir).is_ok() {
            // What came into the old directory since it was checked goes back.
            if let Ok(rd) = std::fs::read_dir(stage) {
                for e in rd.flatten() {
                    let dst = a.dir.join(e.file_name());
                    let retired = removals.iter().any(|n| *n == e.file_name());
                    if !dst.exists() && !retired {
                        let _ = std::fs::rename(e.path(), dst);
                    }
                }
            }
            remove(stage);
            unregister(stage);
            return Ok(());
        }
    }
    // The journal (naming the removals): from here on, a run that finds this stage dead
    // finishes the moves and the removals.
    let mut journal = String::new();
    for n in removals {
        journal.push_str(&n.to_string_lossy());
        journal.push('\n');
    }
    std::fs::write(stage.join(JOURNAL), journal).map_err(|e| Error::io(&a.dir, e))?;
    let r = move_into(stage, &a.root, &mut |_| {
        test_delay();
        Ok(())
    });
    if r.is_ok() {
        for n in removals {
            let _ = std::fs::remove_file(a.dir.join(n));
        }
    }
    remove(stage);
    unregister(stage);
    r.map_err(|e| Error::io(&a.dir, e))
}

/// Commits temporary files inside their directory: a journal, then the renames, then the
/// `removals` (journaled as lines with no temporary name).
fn commit_in_place(a: &Area, removals: &[std::ffi::OsString]) -> Result<(), Error> {
    let journal = a.dir.join(unique("bag2mat", JOURNAL_SUFFIX));
    let mut text = String::new();
    for (tmp, target) in &a.files {
        if let (Some(t), Some(g)) = (tmp.file_name(), target.file_name()) {
            text.push_str(&format!(
                "{}\t{}\n",
                t.to_string_lossy(),
                g.to_string_lossy()
            ));
        }
    }
    for n in removals {
        text.push_str(&format!("\t{}\n", n.to_string_lossy()));
    }
    std::fs::write(&journal, text).map_err(|e| Error::io(&a.dir, e))?;
    let mut err = None;
    for (tmp, target) in &a.files {
        if err.is_none() {
            test_delay();
            if let Err(e) = std::fs::rename(tmp, target) {
                err = Some(Error::io(target, e));
            }
        }
        if err.is_some() {
            remove(tmp);
        }
        unregister(tmp);
    }
    if err.is_none() {
        for n in removals {
            let _ = std::fs::remove_file(a.dir.join(n));
        }
    }
    let _ = std::fs::remove_file(&journal);
    err.map_or(Ok(()), Err)
}

/// Several outputs committed together: every output written through a staged
/// [`super::output::Outputs`] (files, plots, directories) waits in its stage;
/// [`Staging::commit`] puts them all in place (see the module doc), and dropping it
/// uncommitted removes them all. A run that fails half way therefore leaves none of its
/// outputs — not even the output directory it would have made — and never a mix of old
/// and new ones. Stagings are independent: runs in one process stage apart.
#[derive(Debug)]
pub(super) struct Staging {
    stage: Stage,
}

impl Staging {
    /// Starts a stage.
    pub(super) fn begin() -> Staging {
        Staging {
            stage: Stage(Arc::new(Mutex::new(Some(Staged::default())))),
        }
    }

    /// The stage the temporary paths written in it record themselves in.
    pub(super) fn stage(&self) -> &Stage {
        &self.stage
    }

    /// Puts every staged output in place. If that fails, what was not yet in place is
    /// removed and the error names the first failure.
    pub(super) fn commit(self) -> Result<(), Error> {
        let staged = lock(&self.stage.0).take().unwrap_or_default();
        let mut err = None;
        for (tmp, target) in &staged.pairs {
            if err.is_none()
                && let Err(e) = std::fs::rename(tmp, target)
            {
                err = Some(Error::io(target, e));
            }
            if err.is_some() {
                remove(tmp);
            }
            unregister(tmp);
        }
        let mut areas = staged.areas;
        areas.sort_by(|a, b| a.root.cmp(&b.root));
        let mut removals = staged.removals;
        for a in &areas {
            // the removals in this area's directory go with its commit
            let (mine, rest): (Vec<_>, Vec<_>) =
                removals.into_iter().partition(|(d, _)| *d == a.dir);
            removals = rest;
            let mine: Vec<std::ffi::OsString> = mine.into_iter().map(|(_, n)| n).collect();
            if err.is_none() {
                if let Err(e) = commit_area(a, &mine) {
                    err = Some(e);
                }
            } else {
                discard(a);
            }
        }
        // removals in a directory this run writes nothing into
        if err.is_none() {
            for (d, n) in removals {
                let _ = std::fs::remove_file(d.join(n));
            }
        }
        err.map_or(Ok(()), Err)
    }
}

/// Removes an area's staged files and its stage.
fn discard(a: &Area) {
    for (tmp, _) in &a.files {
        remove(tmp);
        unregister(tmp);
    }
    if let Some(s) = &a.stage {
        remove(s);
        unregister(s);
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if let Some(staged) = lock(&self.stage.0).take() {
            for (tmp, _) in &staged.pairs {
                remove(tmp);
                unregister(tmp);
            }
            for a in &staged.areas {
                discard(a);
            }
        }
    }
}
