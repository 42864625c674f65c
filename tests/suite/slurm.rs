//! A single-node Slurm cluster for the farm tests: Debian's munged, slurmctld and slurmd started
//! as plain processes (no systemd) with a minimal configuration in a folder of their own, on
//! free ports, and stopped when the test ends.

use std::path::{Path, PathBuf};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// The daemons of one cluster; dropped, they stop.
pub struct Cluster {
    dir: PathBuf,
    bin: PathBuf,
    daemons: Vec<Child>,
}

/// A file in the cluster's log folder for a daemon's output (they log there too).
fn log(dir: &Path, name: &str) -> std::fs::File {
    std::fs::File::create(dir.join("log").join(name)).unwrap()
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

impl Cluster {
    /// Starts munged, slurmctld and slurmd under `dir`; `sbatch` names the client tools' folder.
    /// Panics (with the daemons' logs) if the node is not idle within 30 s.
    pub fn start(dir: &Path, sbatch: &Path) -> Self {
        for sub in ["munge", "state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(dir.join("munge"), std::fs::Permissions::from_mode(0o700)).unwrap();
        let key: Vec<u8> = (0..128).map(|i| (i * 73 + std::process::id() as usize) as u8).collect();
        std::fs::write(dir.join("munge/munge.key"), key).unwrap();
        std::fs::set_permissions(dir.join("munge/munge.key"), std::fs::Permissions::from_mode(0o600)).unwrap();
        let socket = dir.join("munge/socket");
        let munged = Command::new("munged")
            .arg("--foreground")
            .arg("--force")
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--key-file={}", dir.join("munge/munge.key").display()))
            .arg(format!("--log-file={}", dir.join("log/munged.log").display()))
            .arg(format!("--pid-file={}", dir.join("munge/pid").display()))
            .arg(format!("--seed-file={}", dir.join("munge/seed").display()))
            .stdout(log(dir, "munged.out"))
            .stderr(log(dir, "munged.err"))
            .spawn()
            .expect("munged starts (apt-get install munge)");
        let user = std::env::var("USER").unwrap_or_else(|_| "root".into());
        let d = dir.display();
        let config = format!(
            "ClusterName=indratest\nSlurmctldHost=localhost\nSlurmUser={user}\nSlurmdUser={user}\n\
             AuthType=auth/munge\nAuthInfo=socket={socket}\nCredType=cred/munge\n\
             SlurmctldPort={ctld}\nSlurmdPort={slurmd}\nStateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nSchedulerType=sched/backfill\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\nReturnToService=2\nMpiDefault=none\n\
             JobCompType=jobcomp/none\nJobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             NodeName=localhost CPUs={cpus} State=UNKNOWN\n\
             PartitionName=indra Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n",
            socket = socket.display(),
            ctld = free_port(),
            slurmd = free_port(),
            cpus = std::thread::available_parallelism().map_or(2, |n| n.get()),
        );
        std::fs::write(dir.join("slurm.conf"), config).unwrap();
        let bin = sbatch.parent().unwrap_or(Path::new("/usr/bin")).to_path_buf();
        let mut cluster = Self { dir: dir.to_path_buf(), bin, daemons: vec![munged] };
        // Each daemon in the foreground, as a child of the test.
        for (daemon, extra) in [("slurmctld", &["-D", "-i"][..]), ("slurmd", &["-D", "-N", "localhost"][..])] {
            let child = Command::new(daemon)
                .args(extra)
                .env("SLURM_CONF", dir.join("slurm.conf"))
                .stdout(log(dir, &format!("{daemon}.out")))
                .stderr(log(dir, &format!("{daemon}.err")))
                .spawn()
                .unwrap_or_else(|e| panic!("{daemon} starts (apt-get install slurm-wlm): {e}"));
            cluster.daemons.push(child);
        }
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let o = cluster.command("sinfo").args(["-h", "-o", "%T"]).output().unwrap();
            if String::from_utf8_lossy(&o.stdout).trim() == "idle" {
                return cluster;
            }
            assert!(Instant::now() < deadline, "the Slurm node is not idle after 30 s:\n{}", cluster.daemon_logs());
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// A command of the cluster's client tools, pointed at its configuration.
    pub fn command(&self, program: &str) -> Command {
        let path = std::env::var("PATH").unwrap_or_default();
        let mut command = Command::new(program);
        command.env("SLURM_CONF", self.dir.join("slurm.conf")).env("PATH", format!("{}:{path}", self.bin.display()));
        command
    }

    /// The daemons' logs, for a failure's message.
    pub fn daemon_logs(&self) -> String {
        read_all(&self.dir.join("log"))
    }

    /// Every job's output in `folder`, and the daemons' logs.
    pub fn job_logs(&self, folder: &Path) -> String {
        format!("{}\n{}", read_all(folder), self.daemon_logs())
    }
}

fn read_all(folder: &Path) -> String {
    let mut files: Vec<PathBuf> =
        std::fs::read_dir(folder).map(|d| d.flatten().map(|e| e.path()).collect()).unwrap_or_default();
    files.sort();
    files.iter().map(|f| format!("== {}\n{}", f.display(), std::fs::read_to_string(f).unwrap_or_default())).collect()
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for child in self.daemons.iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
