"""Every command example of README.md, run and timed (issue 34, item 4).

Run from the repository root::

    .venv/bin/python benchmarks/bench_readme.py                   # every example, 60 s limit
    .venv/bin/python benchmarks/bench_readme.py --timeout 300     # a longer limit
    .venv/bin/python benchmarks/bench_readme.py --only kubo --keep /tmp/out   # a subset; keep the outputs

The examples are read from README.md itself (so the table stays true when the README
changes): every line starting with ``nlgrd`` in a ``bash`` block, every inline
```nlgrd ...``` naming a file of the repository, and every ``python`` block that imports
nlgrd. Each runs in a fresh temporary directory (the repository's ``data/`` linked into
it, as when run from a clone), with stdout to a file and stderr on a pseudo-terminal (the
command sees a terminal, as a user does: that is where it draws its tqdm bar), under a
timeout. The table gives the wall time, the CPU time of the command and its children, the
exit code, and whether a tqdm bar appeared on stderr; ``uptime`` is printed before and
after (the machine's load moves every figure). Examples that need something outside the
repository (a Dask scheduler, a file the README does not ship) are listed as skipped.
Figures and machine in benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import fcntl
import os
import pty
import re
import resource
import shlex
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import termios
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
# a tqdm bar: " 40%|████      | 4/10 [00:01<00:01, 3.9it/s]"
TQDM_BAR = re.compile(r"\d+%\|.*\|\s*\d+/\d+ \[")
NEEDS = {"--scheduler": "a Dask scheduler", "--batch": "a runs file the README does not ship"}


def _bash_commands(text: str) -> list[str]:
    """The ``nlgrd ...`` lines of the bash blocks, without their comments."""
    out = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.strip()
            if line.startswith("nlgrd"):
                out.append(line.split(" #")[0].strip())
    return out


def _inline_commands(text: str) -> list[str]:
    """Inline ```nlgrd sub file ...``` examples whose file is in the repository."""
    out = []
    for cmd in re.findall(r"`(nlgrd [a-z]+ [^`]+)`", text):
        words = shlex.split(cmd)
        if len(words) > 2 and (ROOT / words[2]).is_file():
            out.append(cmd.strip())
    return out


def _python_blocks(text: str) -> list[str]:
    return [b for b in re.findall(r"```python\n(.*?)```", text, flags=re.S) if "import nlgrd" in b]


def examples(readme: Path = ROOT / "README.md") -> list[tuple[str, str]]:
    """(kind, text) of every example, in the README's order of kinds: bash, inline, python."""
    text = readme.read_text()
    seen, out = set(), []
    for kind, items in (("bash", _bash_commands(text)), ("bash", _inline_commands(text))):
        for c in items:
            if c not in seen:
                seen.add(c)
                out.append((kind, c))
    out += [("python", b) for b in _python_blocks(text)]
    return out


def _drain(fd: int, sink: list[bytes]) -> None:
    while True:
        try:
            chunk = os.read(fd, 65536)
        except OSError:
            return
        if not chunk:
            return
        sink.append(chunk)


def run(kind: str, text: str, timeout: float, keep: Path | None) -> dict:
    """Run one example in a temporary directory; its wall and CPU time, rc and bar."""
    work = Path(tempfile.mkdtemp(prefix="nlgrd-readme-"))
    (work / "data").symlink_to(ROOT / "data")
    if kind == "python":
        (work / "example.py").write_text(text)
        argv = [sys.executable, "example.py"]
    else:
        words = shlex.split(text)
        argv = [str(BIN / words[0]), *words[1:]]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", COLUMNS="100")
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a 100-column terminal
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(work / "stdout.txt", "wb") as out:
        proc = subprocess.Popen(
            argv,
            cwd=work,
            stdout=out,
            stderr=slave,
            stdin=subprocess.DEVNULL,
            env=env,
            start_new_session=True,
        )
    os.close(slave)
    chunks: list[bytes] = []
    reader = threading.Thread(target=_drain, args=(master, chunks), daemon=True)
    reader.start()
    try:
        rc = proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        rc = None
    wall = time.perf_counter() - t0
    reader.join(timeout=5)
    os.close(master)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    err = b"".join(chunks).decode(errors="replace")
    (work / "stderr.txt").write_text(err)
    if keep is not None:
        dest = keep / f"{len(list(keep.glob('*'))):02d}"
        (work / "data").unlink()
        shutil.copytree(work, dest)
        (dest / "command.txt").write_text(text)
    shutil.rmtree(work, ignore_errors=True)
    return {"wall": wall, "cpu": cpu, "rc": rc, "bar": bool(TQDM_BAR.search(err)), "tail": err.strip()[-300:]}


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per example (default 60)")
    ap.add_argument("--only", default=None, help="run only the examples containing this text")
    ap.add_argument("--keep", type=Path, default=None, help="copy each example's directory here")
    ap.add_argument("--list", action="store_true", help="list the examples and stop")
    ap.add_argument("--readme", type=Path, default=ROOT / "README.md", help="file read (README.md)")
    args = ap.parse_args(argv)
    todo = examples(args.readme)
    if args.only:
        todo = [e for e in todo if args.only in e[1]]
    if args.list:
        for kind, text in todo:
            print(f"[{kind}] {text}")
        return 0
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
    print(f"uptime before: {_uptime()}", flush=True)
    rows = []
    for kind, text in todo:
        label = text if kind == "bash" else "python: " + " ".join(text.split("\n")[2:3])
        need = next((v for k, v in NEEDS.items() if kind == "bash" and k in text.split()), None)
        if need:
            rows.append((label, "skipped", "", "", f"needs {need}"))
            print(f"skip {label}: needs {need}", flush=True)
            continue
        r = run(kind, text, args.timeout, args.keep)
        rc = "timeout" if r["rc"] is None else str(r["rc"])
        rows.append((label, f"{r['wall']:.1f}", f"{r['cpu']:.1f}", rc, "yes" if r["bar"] else "no"))
        print(
            f"{r['wall']:7.1f} s wall {r['cpu']:7.1f} s CPU  rc {rc:>7}  bar {rows[-1][4]:>3}  {label}",
            flush=True,
        )
        if r["rc"] not in (0, None):
            print("   " + r["tail"].replace("\n", "\n   "), flush=True)
    print(f"uptime after: {_uptime()}\n")
    print("| command | wall [s] | CPU [s] | rc | tqdm bar |\n|---|---|---|---|---|")
    for label, wall, cpu, rc, bar in rows:
        print(f"| `{label}` | {wall} | {cpu} | {rc} | {bar} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
