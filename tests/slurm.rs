//! `scripts/slurm-dataset.sh` on a real one-node Slurm cluster started here (munged,
//! slurmctld, slurmd, each started by hand and stopped at the end): an array of 3 shards of
//! a 12-sample set and the merge after them give the unsharded set, byte for byte (all but
//! `dataset.json`'s command line). Skipped with a message where Slurm cannot start (not
//! installed, not root, a daemon fails): `apt-get install slurm-wlm munge` on Debian.

mod sets;

use sets::{assert_complete, dataset, files, scratch};
use std::fs;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The daemons of a one-node cluster, killed (by pid) when dropped.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<Child>,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Cancels whatever a failed test left queued or running before the daemons go (only
        // while all three run: a client without its controller waits a minute).
        let alive = self.daemons.len() == 3
            && self
                .daemons
                .iter_mut()
                .all(|d| matches!(d.try_wait(), Ok(None)));
        if alive {
            if let Ok(mut scancel) = self
                .command("scancel")
                .args(["--user", "root"])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
            {
                let start = Instant::now();
                while matches!(scancel.try_wait(), Ok(None)) && start.elapsed().as_secs() < 10 {
                    std::thread::sleep(Duration::from_millis(50));
                }
                let _ = scancel.kill();
                let _ = scancel.wait();
            }
        }
        for d in self.daemons.iter_mut().rev() {
            let _ = d.kill();
            let _ = d.wait();
        }
    }
}

impl Cluster {
    /// A Slurm client command talking to this cluster.
    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Starts munged, slurmctld and slurmd in `dir`, or says why it cannot.
    fn start(dir: &Path) -> Result<Cluster, String> {
        for tool in [
            "munged",
            "slurmctld",
            "slurmd",
            "sbatch",
            "scontrol",
            "sinfo",
        ] {
            if find(tool).is_none() {
                return Err(format!("{tool} not found"));
            }
        }
        let uid = Command::new("id")
            .arg("-u")
            .output()
            .map_err(|e| e.to_string())?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("not root (slurmd must start jobs as their user)".into());
        }
        fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let conf = dir.join("slurm.conf");
        let mut cluster = Cluster {
            dir: dir.to_path_buf(),
            conf: conf.clone(),
            daemons: Vec::new(),
        };
        let socket = dir.join("munge.socket");
        let key = dir.join("munge.key");
        fs::write(&key, read_random(1024)?).map_err(|e| e.to_string())?;
        set_mode(&key, 0o400);
        set_mode(dir, 0o755);
        cluster.spawn(
            "munged",
            &[
                "-F",
                "--force",
                &format!("--key-file={}", key.display()),
                &format!("--socket={}", socket.display()),
                &format!("--pid-file={}", dir.join("munged.pid").display()),
                &format!("--log-file={}", dir.join("munged.log").display()),
                &format!("--seed-file={}", dir.join("munged.seed").display()),
            ],
        )?;
        cluster.wait_for("munged's socket", || socket.exists())?;
        fs::write(&conf, slurm_conf(dir, &socket)?).map_err(|e| e.to_string())?;
        let conf_arg = conf.display().to_string();
        cluster.spawn("slurmctld", &["-D", "-i", "-f", &conf_arg])?;
        cluster.spawn("slurmd", &["-D", "-N", "localhost", "-f", &conf_arg])?;
        let conf = cluster.conf.clone();
        cluster.wait_for("the node to be idle", || {
            Command::new("sinfo")
                .env("SLURM_CONF", &conf)
                .args(["-h", "-o", "%T"])
                .output()
                .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        })?;
        Ok(cluster)
    }

    fn spawn(&mut self, program: &str, args: &[&str]) -> Result<(), String> {
        let log = fs::File::create(self.dir.join(format!("{program}.out"))).unwrap();
        let child = Command::new(find(program).unwrap())
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("{program}: {e}"))?;
        self.daemons.push(child);
        Ok(())
    }

    /// Polls `ready` for up to 30 s; a daemon that exits meanwhile fails at once.
    fn wait_for(&mut self, what: &str, mut ready: impl FnMut() -> bool) -> Result<(), String> {
        let start = Instant::now();
        while !ready() {
            for d in &mut self.daemons {
                if let Ok(Some(status)) = d.try_wait() {
                    return Err(format!(
                        "a daemon exited ({status}) waiting for {what}: {}",
                        self.logs()
                    ));
                }
            }
            if start.elapsed() > Duration::from_secs(30) {
                return Err(format!("no {what} after 30 s: {}", self.logs()));
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        Ok(())
    }

    /// The daemons' output, for a failure's message.
    fn logs(&self) -> String {
        ["munged", "slurmctld", "slurmd"]
            .iter()
            .map(|d| {
                let text =
                    fs::read_to_string(self.dir.join(format!("{d}.out"))).unwrap_or_default();
                let tail: Vec<&str> = text.lines().rev().take(5).collect();
                format!(
                    "[{d}] {}",
                    tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// Waits until the merge job `merge` and the array job `array` have completed; panics
    /// with their states and the jobs' logs in `logs` if one fails or 180 s pass.
    fn wait_done(&self, merge: &str, array: &str, logs: &Path) {
        let logs = || {
            fs::read_dir(logs)
                .map(|d| {
                    d.flatten()
                        .map(|e| {
                            let text = fs::read_to_string(e.path()).unwrap_or_default();
                            format!("{}: {}", e.file_name().to_string_lossy(), text.trim())
                        })
                        .collect::<Vec<_>>()
                        .join("\n")
                })
                .unwrap_or_default()
        };
        let start = Instant::now();
        loop {
            let state = self.job_state(merge);
            match state.as_deref() {
                Some("COMPLETED") => break,
                Some("PENDING" | "RUNNING" | "CONFIGURING" | "COMPLETING") => {}
                other => panic!(
                    "merge job {merge}: {other:?}; array {array}: {:?}\n{}",
                    self.job_state(array),
                    logs()
                ),
            }
            assert!(
                start.elapsed() < Duration::from_secs(180),
                "the jobs did not finish in 180 s: merge {state:?}, array {:?}\n{}",
                self.job_state(array),
                logs()
            );
            std::thread::sleep(Duration::from_millis(250));
        }
        assert_eq!(self.job_state(array).as_deref(), Some("COMPLETED"));
    }

    /// A job's state (`COMPLETED`, `PENDING`, ...), or `None` once Slurm forgot it.
    fn job_state(&self, id: &str) -> Option<String> {
        let o = self
            .command("scontrol")
            .args(["show", "job", "-o", id])
            .output()
            .ok()?;
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let states: Vec<&str> = text
            .split_whitespace()
            .filter_map(|f| f.strip_prefix("JobState="))
            .collect();
        // An array job's tasks: the first one not done, or COMPLETED when all are.
        states
            .iter()
            .find(|s| **s != "COMPLETED")
            .or(states.first())
            .map(|s| s.to_string())
    }
}

/// The slurm.conf of a one-node cluster in `dir`, on two free ports.
fn slurm_conf(dir: &Path, munge_socket: &Path) -> Result<String, String> {
    let port = || {
        TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map(|a| a.port())
            .map_err(|e| e.to_string())
    };
    let (ctld_port, d_port) = (port()?, port()?);
    for sub in ["state", "spool"] {
        fs::create_dir_all(dir.join(sub)).map_err(|e| e.to_string())?;
    }
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let d = dir.display();
    Ok(format!(
        "ClusterName=geltiptest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket={socket}
CredType=cred/munge
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldPort={ctld_port}
SlurmdPort={d_port}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/builtin
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MailProg=/bin/true
NodeName=localhost NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
",
        socket = munge_socket.display(),
    ))
}

/// A program on PATH or in the sbin directories (daemons live there).
fn find(program: &str) -> Option<PathBuf> {
    let path = std::env::var("PATH").unwrap_or_default();
    let mut dirs: Vec<&str> = path.split(':').collect();
    dirs.extend(["/usr/sbin", "/sbin", "/usr/local/sbin"]);
    dirs.into_iter()
        .map(|d| Path::new(d).join(program))
        .find(|p| p.is_file())
}

fn read_random(n: usize) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let mut buf = vec![0u8; n];
    fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut buf))
        .map_err(|e| format!("/dev/urandom: {e}"))?;
    Ok(buf)
}

fn set_mode(path: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    let _ = fs::set_permissions(path, fs::Permissions::from_mode(mode));
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm-dataset.sh")
}

/// Runs the script with `args` against `cluster`.
fn submit(cluster: &Cluster, args: &[&str]) -> Output {
    cluster
        .command("bash")
        .arg(script())
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

const SET: [&str; 4] = ["--masks", "--depth-maps", "--noise", "2"];

#[test]
fn slurm_array_of_shards_then_merge_equals_the_unsharded_set() {
    let root = scratch("slurm");
    let cluster = match Cluster::start(&root.join("cluster")) {
        Ok(c) => c,
        Err(why) => {
            eprintln!(
                "skipped: Slurm cannot start here ({why}); on Debian, as root: \
                 apt-get install -y slurm-wlm munge"
            );
            return;
        }
    };
    let out = root.join("merged");
    let geltip = env!("CARGO_BIN_EXE_geltip");
    let mut args = vec![
        "--sensor",
        "paper",
        "--count",
        "12",
        "--seed",
        "5",
        "--shards",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--geltip",
        geltip,
        "--",
    ];
    args.extend(SET);
    args.extend(["--streams", "1", "--jobs", "1"]);
    let o = submit(&cluster, &args);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let ids: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let (array, merge) = (
        ids["array_job"].as_str().unwrap(),
        ids["merge_job"].as_str().unwrap(),
    );
    let start = Instant::now();
    cluster.wait_done(merge, array, &root.join("merged.shards/logs"));
    eprintln!(
        "Slurm: 3 shards and the merge done in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert_complete(&out, 12);

    let whole = root.join("whole");
    let mut args = vec!["--count", "12", "--seed", "5"];
    args.extend(SET);
    dataset(&whole, &args);
    let (fw, fm) = (files(&whole), files(&out));
    assert_eq!(fw.keys().collect::<Vec<_>>(), fm.keys().collect::<Vec<_>>());
    for (k, v) in &fw {
        assert!(
            fm[k] == *v,
            "{k} differs between the Slurm set and the unsharded set"
        );
    }
}
