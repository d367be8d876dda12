//! `glray run --np N`: the program's ranks under Open MPI's mpirun (Debian's `openmpi-bin`),
//! each with glray: LD_PRELOAD (or the drop-in directory) and every GLRAY_* setting forwarded
//! with `-x`, `--allow-run-as-root` only as root and `--oversubscribe` only when the ranks
//! outnumber this machine's cores (and no hosts are given).

use std::ffi::OsString;
use std::process::Command;

/// What `--np`, `--hosts` and `--mpirun-arg` asked for.
pub struct Ranks {
    pub np: u32,
    pub hosts: Option<String>,
    pub extra: Vec<String>,
}

/// The mpirun to use: `MPIRUN` if set, else the one on the PATH.
fn mpirun() -> Result<OsString, String> {
    if let Some(m) = std::env::var_os("MPIRUN") {
        return Ok(m);
    }
    let found = std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).map(|d| d.join("mpirun")).find(|p| p.is_file()))
        .unwrap_or_default();
    found.map(OsString::from).ok_or_else(|| {
        "--np needs Open MPI's mpirun, and none is on the PATH (Debian: apt-get install openmpi-bin; or set MPIRUN)"
            .to_string()
    })
}

/// The mpirun command for `ranks` of `program`, with `env` (set on mpirun itself by the caller)
/// forwarded to every rank, and every GLRAY_* of this environment too.
pub fn command(ranks: &Ranks, env: &[(String, OsString)], program: &[OsString]) -> Result<Command, String> {
    let mut cmd = Command::new(mpirun()?);
    cmd.arg("-np").arg(ranks.np.to_string());
    // SAFETY: getuid cannot fail.
    if unsafe { libc::getuid() } == 0 {
        cmd.arg("--allow-run-as-root");
    }
    match &ranks.hosts {
        Some(h) => {
            cmd.arg("--host").arg(h);
        }
        None => {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            if ranks.np as usize > cores {
                cmd.arg("--oversubscribe");
            }
        }
    }
    let mut names: Vec<String> = env.iter().map(|(k, _)| k.clone()).collect();
    for (k, _) in std::env::vars_os() {
        if let Some(k) = k.to_str().filter(|k| k.starts_with("GLRAY_")) {
            names.push(k.to_string());
        }
    }
    names.sort();
    names.dedup();
    for name in names {
        // `-x NAME` sends the value mpirun itself has (the caller sets it on this command).
        cmd.arg("-x").arg(name);
    }
    cmd.args(&ranks.extra);
    cmd.args(program);
    Ok(cmd)
}
