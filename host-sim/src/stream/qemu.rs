//! Boots a firmware ELF on one of QEMU's Cortex-M4F machines ([`Machine`]) with the firmware's
//! link serial port (the machine's first `-serial`) on a unix socket, and stops it when dropped.
//!
//! The command line (also in docs/firmware.md):
//!
//! ```text
//! qemu-system-arm -machine mps2-an386 -cpu cortex-m4     (or: -machine netduinoplus2)
//!     -icount shift=0 -display none -monitor none
//!     -semihosting-config enable=on,target=native
//!     -chardev socket,id=link,path=DIR/link.sock,server=on,wait=on -serial chardev:link
//!     -kernel FIRMWARE.elf
//! ```
//!
//! `-icount shift=0` makes every guest instruction take exactly 1 ns of virtual time, so the
//! firmware's SysTick cost counter (25 MHz on mps2-an386, 168 MHz on netduinoplus2) counts a fixed
//! number of instructions per tick. QEMU's stdout is the firmware's defmt log (semihosting): with
//! `--defmt-log FILE` it goes to a temporary file beside FILE, renamed over it only when the run
//! ends well ([`Qemu::finish`]), so a failed run leaves an earlier log as it was. QEMU's stderr
//! goes to a file in its scratch directory, quoted when QEMU fails; the directory is removed
//! whatever happens.

use anyhow::{bail, Context};
use std::fs::File;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};
use tempfile::{NamedTempFile, TempDir};

/// `-icount shift` used; instructions per nanosecond of virtual time = 1 / 2^shift.
pub const ICOUNT_SHIFT: u32 = 0;

/// Extra QEMU arguments from `$HOST_SIM_QEMU_ARGS` (split at whitespace), e.g. a TCG plugin:
/// `HOST_SIM_QEMU_ARGS="-plugin firmware/tools/libpcprofile.so,out=profile.txt"`.
pub fn extra_args() -> Vec<String> {
    std::env::var("HOST_SIM_QEMU_ARGS")
        .map(|a| a.split_whitespace().map(String::from).collect())
        .unwrap_or_default()
}

/// The QEMU machine a firmware image is built for (the firmware's board feature).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Machine {
    /// ARM MPS2+ AN386 (Cortex-M4F, 25 MHz): firmware feature `board-mps2-an386`; UART0.
    #[default]
    #[value(name = "mps2-an386")]
    Mps2An386,
    /// Netduino Plus 2 (STM32F405, Cortex-M4F): firmware feature `board-stm32f405`; USART1.
    #[value(name = "netduinoplus2")]
    Netduinoplus2,
}

impl Machine {
    /// QEMU's name of the machine.
    pub fn name(self) -> &'static str {
        match self {
            Machine::Mps2An386 => "mps2-an386",
            Machine::Netduinoplus2 => "netduinoplus2",
        }
    }

    /// `-machine NAME` and, where the machine has a choice, `-cpu`.
    pub fn args(self) -> &'static [&'static str] {
        match self {
            Machine::Mps2An386 => &["-machine", "mps2-an386", "-cpu", "cortex-m4"],
            Machine::Netduinoplus2 => &["-machine", "netduinoplus2"],
        }
    }

    /// The serial port the firmware's link is on (QEMU's first `-serial`).
    pub fn link_port(self) -> &'static str {
        match self {
            Machine::Mps2An386 => "UART0",
            Machine::Netduinoplus2 => "USART1",
        }
    }
}

impl std::fmt::Display for Machine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A running QEMU.
pub struct Qemu {
    child: Child,
    /// The scratch directory (the link's socket, QEMU's stderr, the flash without `--flash-dir`):
    /// removed when dropped, on every path out.
    _dir: TempDir,
    stderr_path: PathBuf,
    /// The defmt log being written, and the file it is renamed to by [`Qemu::finish`].
    defmt_log: Option<(NamedTempFile, PathBuf)>,
}

/// QEMU's command line: `machine` booting `elf`, the link's serial port on the socket `socket`
/// (the guest waits for it to connect), semihosting on, no display, instructions counted.
fn qemu_command(binary: &str, machine: Machine, elf: &Path, socket: &Path) -> Command {
    let mut command = Command::new(binary);
    command
        .args(machine.args())
        .args(["-icount", &format!("shift={ICOUNT_SHIFT}")])
        .args(["-display", "none", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .arg("-chardev")
        .arg(format!(
            "socket,id=link,path={},server=on,wait=on",
            socket.display()
        ))
        .args(["-serial", "chardev:link", "-kernel"])
        .arg(elf)
        .args(extra_args());
    command
}

/// The QEMU binary: `$QEMU_SYSTEM_ARM`, else `qemu-system-arm` on the PATH.
pub fn qemu_binary() -> String {
    std::env::var("QEMU_SYSTEM_ARM").unwrap_or_else(|_| "qemu-system-arm".to_string())
}

impl Qemu {
    /// Boots `elf` on `machine`; the firmware's defmt log goes to `defmt_log` (or is discarded).
    /// Returns once the link's socket is connected (the guest starts then: `wait=on`).
    /// QEMU runs in `flash_dir` (where a firmware built with its `checkpoint` feature keeps its
    /// flash, `rins-flash.bin`), or in a fresh scratch directory.
    pub fn boot(
        elf: &Path,
        machine: Machine,
        defmt_log: Option<&Path>,
        flash_dir: Option<&Path>,
    ) -> anyhow::Result<(Qemu, UnixStream)> {
        if !elf.is_file() {
            bail!("{}: no such firmware ELF", elf.display());
        }
        let elf = &std::fs::canonicalize(elf)?;
        let scratch = tempfile::Builder::new()
            .prefix("host-sim-qemu-")
            .tempdir()
            .context("cannot create QEMU's scratch directory")?;
        let dir = scratch.path().to_path_buf();
        let socket = dir.join("link.sock");
        let stderr_path = dir.join("qemu.stderr");
        let defmt_log = match defmt_log {
            Some(target) => {
                let temp = crate::formats::output_file::temp_beside(target)?;
                Some((temp, target.to_path_buf()))
            }
            None => None,
        };
        let stdout = match &defmt_log {
            Some((temp, target)) => Stdio::from(
                temp.reopen()
                    .with_context(|| format!("{}:0: cannot write", target.display()))?,
            ),
            None => Stdio::null(),
        };
        let binary = qemu_binary();
        let mut command = qemu_command(&binary, machine, elf, &socket);
        command
            .current_dir(flash_dir.unwrap_or(&dir))
            .stdin(Stdio::null())
            .stdout(stdout)
            .stderr(Stdio::from(File::create(&stderr_path)?));
        kill_with_parent(&mut command);
        let child = match command.spawn() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                bail!("{binary} not found: install QEMU (Debian: apt-get install -y qemu-system-arm) or set QEMU_SYSTEM_ARM")
            }
            Err(e) => return Err(e).with_context(|| format!("cannot start {binary}")),
        };
        let qemu = Qemu {
            child,
            _dir: scratch,
            stderr_path,
            defmt_log,
        };
        qemu.connect(&socket)
    }

    /// Waits (20 s at most) for the link's socket to connect; errors if QEMU exits first.
    fn connect(mut self, socket: &Path) -> anyhow::Result<(Qemu, UnixStream)> {
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            if let Some(status) = self.child.try_wait()? {
                bail!(
                    "QEMU exited ({status}) before the link's socket connected: {}",
                    self.stderr_tail()
                );
            }
            if let Ok(stream) = UnixStream::connect(socket) {
                return Ok((self, stream));
            }
            if Instant::now() > deadline {
                bail!(
                    "QEMU's link socket {} did not open within 20 s: {}",
                    socket.display(),
                    self.stderr_tail()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The run ended well: QEMU is stopped and the defmt log, if one was asked for, renamed over
    /// its file (dropped without this, QEMU is stopped and the log's temporary file deleted).
    pub fn finish(mut self) -> anyhow::Result<()> {
        let _ = self.child.kill();
        let _ = self.child.wait();
        match self.defmt_log.take() {
            Some((temp, target)) => crate::formats::output_file::persist(temp, &target),
            None => Ok(()),
        }
    }

    /// QEMU's exit status, if it has exited.
    pub fn exited(&mut self) -> Option<ExitStatus> {
        self.child.try_wait().ok().flatten()
    }

    /// The end of QEMU's stderr, for error messages.
    pub fn stderr_tail(&self) -> String {
        let text = std::fs::read_to_string(&self.stderr_path).unwrap_or_default();
        let tail: String = text
            .chars()
            .rev()
            .take(800)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        if tail.trim().is_empty() {
            "(QEMU printed nothing on stderr)".to_string()
        } else {
            format!("QEMU stderr: {}", tail.trim())
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// QEMU must not outlive this process, even if it is killed.
#[cfg(target_os = "linux")]
fn kill_with_parent(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    // SAFETY: prctl is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        command.pre_exec(|| {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
            Ok(())
        });
    }
}

#[cfg(not(target_os = "linux"))]
fn kill_with_parent(_: &mut Command) {}
