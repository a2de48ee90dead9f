//! One writer per output directory: a lock file held while a run writes there.
//!
//! The lock is the operating system's advisory lock on `<dir>/.geltip.lock` (`flock`), so a
//! run that dies in any way (SIGKILL included) releases it with its process: the next run
//! takes it over with nothing to clean up. The file holds who holds the lock (pid, host,
//! start time), for the error a second run gives; it is removed when the run ends. Where
//! there is no `flock` (other platforms, file systems without locks) runs go unguarded,
//! with a warning.

use crate::error::{GeltipError, Result};
use std::fs;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// The lock file's name in a locked directory.
pub const LOCK_FILE: &str = ".geltip.lock";

/// Holds a directory's lock until dropped.
#[derive(Debug)]
pub struct DirLock {
    path: PathBuf,
    /// `None` where the file system has no locks: nothing is held.
    file: Option<fs::File>,
}

impl DirLock {
    /// Takes the lock of `dir` (which must exist) for this process, or fails at once, naming
    /// the run that holds it, with an error about `what` (e.g. `out <dir>`).
    ///
    /// On a file system without advisory locks a warning is logged and the run goes on
    /// unguarded.
    pub fn acquire(dir: &Path, what: &str) -> Result<DirLock> {
        let path = dir.join(LOCK_FILE);
        loop {
            let mut file = fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(|e| GeltipError::io(&path, e))?;
            match try_lock(&file, true) {
                Ok(true) => {}
                Ok(false) => {
                    return Err(GeltipError::input(
                        what,
                        format!(
                            "is being written by another run ({}); wait for it to end, or stop \
                             it and rerun to resume",
                            holder_of(&mut file)
                        ),
                    ));
                }
                Err(e) if unsupported(&e) => {
                    log::warn!(
                        "{}: the file system has no file locks ({e}): not guarded against a \
                         second run writing there at once",
                        dir.display()
                    );
                    return Ok(DirLock { path, file: None });
                }
                Err(e) => return Err(GeltipError::io(&path, e)),
            }
            // A run that ended between our open and our lock removed the file we locked:
            // that lock guards nothing, so lock the file now at the path.
            if same_file(&file, &path) {
                write_holder(&mut file).map_err(|e| GeltipError::io(&path, e))?;
                return Ok(DirLock {
                    path,
                    file: Some(file),
                });
            }
        }
    }

    /// If another process holds `dir`'s lock: who (as in [`DirLock::acquire`]'s error).
    pub fn holder(dir: &Path) -> Result<Option<String>> {
        let path = dir.join(LOCK_FILE);
        let mut file = match fs::File::open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(GeltipError::io(&path, e)),
        };
        match try_lock(&file, false) {
            Ok(true) => Ok(None),
            Ok(false) => Ok(Some(holder_of(&mut file))),
            Err(e) if unsupported(&e) => Ok(None),
            Err(e) => Err(GeltipError::io(&path, e)),
        }
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Removed while still locked: a run waiting on this file sees it gone and retries.
        if self.file.is_some() {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Takes `file`'s advisory lock (exclusive or shared) without waiting: `Ok(false)` when
/// another open file holds it. Released when the file is closed.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn try_lock(file: &fs::File, exclusive: bool) -> std::io::Result<bool> {
    use std::os::fd::AsRawFd;
    let how = if exclusive {
        libc::LOCK_EX
    } else {
        libc::LOCK_SH
    };
    // SAFETY: flock on a file descriptor this `File` owns; no memory is passed.
    if unsafe { libc::flock(file.as_raw_fd(), how | libc::LOCK_NB) } == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(false),
        _ => Err(e),
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn try_lock(_file: &fs::File, _exclusive: bool) -> std::io::Result<bool> {
    Err(std::io::ErrorKind::Unsupported.into())
}

/// Errors of a file system (or platform) without advisory locks.
fn unsupported(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::Unsupported
        || matches!(
            e.raw_os_error(),
            Some(37 /* ENOLCK */) | Some(38 /* ENOSYS */) | Some(95 /* EOPNOTSUPP */)
        )
}

#[cfg(unix)]
fn same_file(file: &fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &fs::File, path: &Path) -> bool {
    path.exists()
}

fn write_holder(file: &mut fs::File) -> std::io::Result<()> {
    let started = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    let text = format!(
        "pid {} on {}, started {}\n",
        std::process::id(),
        host_name(),
        utc_time(started)
    );
    file.set_len(0)?;
    file.seek(SeekFrom::Start(0))?;
    file.write_all(text.as_bytes())
}

/// The holder's line from a lock file. It is written just after the lock is taken, so a
/// reader that finds it empty waits a moment for it.
fn holder_of(file: &mut fs::File) -> String {
    for _ in 0..20 {
        let mut text = String::new();
        if file.seek(SeekFrom::Start(0)).is_ok() && file.read_to_string(&mut text).is_ok() {
            let line = text.trim();
            if !line.is_empty() {
                return line.to_string();
            }
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    "a process that has not said who it is".to_string()
}

fn host_name() -> String {
    ["/proc/sys/kernel/hostname", "/etc/hostname"]
        .iter()
        .find_map(|p| {
            fs::read_to_string(p)
                .ok()
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
        })
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "an unknown host".to_string())
}

/// `since_epoch` as `YYYY-MM-DD hh:mm:ss UTC`.
fn utc_time(since_epoch: Duration) -> String {
    let secs = since_epoch.as_secs();
    let (days, rest) = ((secs / 86_400) as i64, secs % 86_400);
    // Days since 1970-01-01 to a civil date (Howard Hinnant's days_from_civil, inverted).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_times() {
        assert_eq!(utc_time(Duration::ZERO), "1970-01-01 00:00:00 UTC");
        assert_eq!(
            utc_time(Duration::from_secs(951_782_400)),
            "2000-02-29 00:00:00 UTC"
        );
        assert_eq!(
            utc_time(Duration::from_secs(1_795_573_078)),
            "2026-11-25 02:17:58 UTC"
        );
    }

    #[test]
    fn a_second_lock_is_refused_and_a_released_one_taken() {
        let dir = std::env::temp_dir().join(format!("geltip-lock-test-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let first = DirLock::acquire(&dir, "out d").unwrap();
        assert!(DirLock::holder(&dir).unwrap().is_some());
        let e = DirLock::acquire(&dir, "out d").unwrap_err().to_string();
        let me = format!("pid {} on ", std::process::id());
        assert!(
            e.starts_with("out d: is being written by another run (") && e.contains(&me),
            "{e}"
        );
        drop(first);
        assert!(!dir.join(LOCK_FILE).exists());
        assert!(DirLock::holder(&dir).unwrap().is_none());
        // A lock file left behind by a process that is gone holds no lock.
        fs::write(
            dir.join(LOCK_FILE),
            "pid 1 on elsewhere, started long ago\n",
        )
        .unwrap();
        assert!(DirLock::holder(&dir).unwrap().is_none());
        let again = DirLock::acquire(&dir, "out d").unwrap();
        let text = fs::read_to_string(dir.join(LOCK_FILE)).unwrap();
        assert!(text.starts_with(&me), "{text}");
        drop(again);
        fs::remove_dir_all(&dir).unwrap();
    }
}
