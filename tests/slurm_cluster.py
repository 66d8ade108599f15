"""A one-node Slurm cluster on localhost for the tests, from Debian's packages.

munged, slurmctld and slurmd are started in the foreground as children of the
test process (their PIDs kept), with their configuration, keys, state and
logs in a temporary directory and ports picked free; :meth:`LocalSlurm.stop`
cancels what is left in the queue and stops the three by PID. Nothing
outside the directory is touched: the clients find the cluster through
``SLURM_CONF``.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

#: What installs the cluster on Debian 12 (scripts/setup.sh runs it)
INSTALL = "apt-get install -y slurmctld slurmd slurm-client munge"
PROGRAMS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel")


def missing_programs() -> list[str]:
    """Return the cluster's programs that are not installed."""
    paths = os.environ.get("PATH", "") + ":/usr/sbin:/sbin"
    return [p for p in PROGRAMS if shutil.which(p, path=paths) is None]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class LocalSlurm:
    """munge + slurmctld + slurmd on this machine, in ``root``.

    Parameters
    ----------
    root
        An empty directory for the cluster's files.
    cpus
        CPUs of the one node.
    """

    def __init__(self, root: Path, cpus: int) -> None:
        self.root = Path(root)
        self.cpus = cpus
        self.host = socket.gethostname().split(".")[0]
        self.conf = self.root / "slurm.conf"
        self.procs: dict[str, subprocess.Popen[bytes]] = {}

    @property
    def env(self) -> dict[str, str]:
        """The environment in which Slurm's clients talk to this cluster."""
        path = os.environ.get("PATH", "") + ":/usr/sbin:/sbin"
        return {**os.environ, "SLURM_CONF": str(self.conf), "PATH": path}

    def _write(self) -> None:
        r = self.root
        for d in ("state", "spool", "munge"):
            (r / d).mkdir(parents=True, exist_ok=True)
        (r / "munge").chmod(0o700)
        key = r / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o400)
        lines = {
            "ClusterName": "foamsilo-test",
            "SlurmctldHost": f"{self.host}(127.0.0.1)",
            "SlurmUser": "root",
            "SlurmdUser": "root",
            "SlurmctldPort": _free_port(),
            "SlurmdPort": _free_port(),
            "AuthType": "auth/munge",
            "AuthInfo": f"socket={r / 'munge' / 'munge.socket'}",
            "CredType": "cred/munge",
            "StateSaveLocation": r / "state",
            "SlurmdSpoolDir": r / "spool",
            "SlurmctldPidFile": r / "slurmctld.pid",
            "SlurmdPidFile": r / "slurmd.pid",
            "SlurmctldLogFile": r / "slurmctld.log",
            "SlurmdLogFile": r / "slurmd.log",
            "ProctrackType": "proctrack/linuxproc",
            "TaskPlugin": "task/none",
            "JobAcctGatherType": "jobacct_gather/none",
            "AccountingStorageType": "accounting_storage/none",
            "JobCompType": "jobcomp/none",
            "SelectType": "select/cons_tres",
            "SelectTypeParameters": "CR_Core",
            "MpiDefault": "none",
            "ReturnToService": 2,
            "KillWait": 5,
            # a finished job stays known to scontrol for 10 minutes (no accounting here)
            "MinJobAge": 600,
        }
        text = "".join(f"{k}={v}\n" for k, v in lines.items())
        text += f"NodeName={self.host} NodeAddr=127.0.0.1 CPUs={self.cpus} State=UNKNOWN\n"
        text += "PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n"
        self.conf.write_text(text)

    def _start(self, name: str, argv: list[str]) -> None:
        log = (self.root / f"{name}.out").open("wb")
        self.procs[name] = subprocess.Popen(
            argv, env=self.env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )

    def start(self, timeout: float = 60.0) -> None:
        """Start the three daemons and wait until the node is idle.

        Raises
        ------
        RuntimeError
            A daemon died or the node did not come up; the message holds the logs.
        """
        self._write()
        m = self.root / "munge"
        self._start("munged", ["munged", "--foreground", "--force",
                               f"--socket={m / 'munge.socket'}", f"--key-file={m / 'munge.key'}",
                               f"--pid-file={m / 'munged.pid'}", f"--log-file={m / 'munged.log'}",
                               f"--seed-file={m / 'munged.seed'}"])  # fmt: skip
        self._wait(lambda: (m / "munge.socket").exists(), 20.0, "munged")
        self._start("slurmctld", ["slurmctld", "-D", "-f", str(self.conf)])
        self._start("slurmd", ["slurmd", "-D", "-f", str(self.conf), "-N", self.host])

        def idle() -> bool:
            res = subprocess.run(["sinfo", "--noheader", "--format=%T"], env=self.env,
                                 capture_output=True, text=True)  # fmt: skip
            return res.returncode == 0 and res.stdout.strip() == "idle"

        self._wait(idle, timeout, "the node")

    def _wait(self, ready: object, timeout: float, what: str) -> None:
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            if callable(ready) and ready():
                return
            dead = [n for n, p in self.procs.items() if p.poll() is not None]
            if dead:
                break
            time.sleep(0.5)
        self.stop()
        logs = "\n".join(
            f"--- {f.name}\n{f.read_text(errors='replace')[-1500:]}"
            for f in sorted(self.root.glob("*.out")) + sorted(self.root.glob("*.log"))
        )
        raise RuntimeError(f"the local Slurm did not start ({what}):\n{logs}")

    def stop(self) -> None:
        """Cancel the jobs left in the queue, then stop slurmd, slurmctld and munged by PID."""
        if "slurmctld" in self.procs and self.procs["slurmctld"].poll() is None:
            subprocess.run(["scancel", "--full", f"--user={os.getuid()}"], env=self.env,
                           capture_output=True, timeout=30)  # fmt: skip
            t0 = time.monotonic()
            while time.monotonic() - t0 < 30:
                res = subprocess.run(["squeue", "--noheader"], env=self.env, capture_output=True,
                                     text=True, timeout=30)  # fmt: skip
                if res.returncode != 0 or not res.stdout.strip():
                    break
                time.sleep(1)
        for name in ("slurmd", "slurmctld", "munged"):
            proc = self.procs.pop(name, None)
            if proc is None or proc.poll() is not None:
                continue
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
