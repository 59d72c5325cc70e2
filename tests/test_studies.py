"""Studies on Dask: the same summary on every executor, worker loss, resume, loopback only.

The 16-task study is Kubo's rig (data/case_studies/kubo.toml) over backlash x mesh
damping, 7 speeds up at H = 5 without stability: about 0.3-1.5 s per task, so that the
comparisons below test the machinery, not the solver (which other modules check).

- Byte-identical ``summary.csv`` serially, on the embedded 2-worker ``LocalCluster`` and
  on a cluster of ``dask scheduler`` + two ``dask worker`` processes started here on
  127.0.0.1. Each task runs with one BLAS thread in every executor and the summary is
  read back from the per-task JSON records (floats round-trip exactly), so any byte of
  difference is a real difference of the numbers.
- A worker process killed (SIGKILL, by its pid) after the first finished task: the
  study completes and its summary equals the undisturbed one.
- ``nlgrd study`` interrupted by SIGINT after three tasks (the fourth held until the
  signal): exit 130; the rerun computes exactly the tasks that were not finished
  (counted in its output) and leaves the finished records untouched (their bytes
  compared).
- The embedded cluster's listening sockets, read from this process and its children
  with psutil: all on the loopback interface, the dashboard's among them.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from nlgrd.studies.study_file import load_study
from nlgrd.studies.study_runner import local_cluster, run_study

ROOT = Path(__file__).resolve().parents[1]
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
NLGRD = [sys.executable, "-m", "nlgrd.cli"]

STUDY = f"""version = 1
name = "16 tasks"
model = "{KUBO.as_posix()}"
[analysis]
rpm = [6000.0, 12000.0, 7]
direction = "up"
harmonics = 5
stability = false
[[axes]]
key = "gear_pairs[0].geometry.backlash"
values = [50e-6, 100e-6, 150e-6, 200e-6]
[[axes]]
key = "gear_pairs[0].damping_ratio"
range = [0.02, 0.08, 4]
"""


@pytest.fixture(scope="module")
def study_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("study") / "s16.toml"
    path.write_text(STUDY)
    return path


@pytest.fixture(scope="module")
def serial(study_file) -> Path:
    out = study_file.parent / "serial"
    run = run_study(load_study(study_file), out, executor="serial", progress=False)
    assert (run.tasks, run.computed, run.failed) == (16, 16, 0)
    return out


def test_serial_study_writes_every_table(serial):
    summary = pd.read_csv(serial / "summary.csv")
    assert len(summary) == 16 and (summary["status"] == "done").all()
    # the grid: every backlash with every damping, last axis fastest
    assert summary["gear_pairs[0].geometry.backlash [m]"].tolist() == [
        b for b in (5e-5, 1e-4, 1.5e-4, 2e-4) for _ in range(4)
    ]
    assert summary["dslr_peak [-]"].gt(1).all()
    points = pd.read_parquet(serial / "points.parquet")
    assert len(points) == 16 * 7 and "gear_pairs[0].damping_ratio [-]" in points
    # xarray-compatible: the grid table has a full product index over the axes
    xr = pytest.importorskip("xarray")
    ds = xr.Dataset.from_dataframe(pd.read_parquet(serial / "grid.parquet"))
    assert ds["dslr_peak [-]"].shape == (4, 4)
    assert not ds["dslr_peak [-]"].isnull().any()


@pytest.mark.slow
def test_local_cluster_gives_the_serial_bytes(study_file, serial):
    out = study_file.parent / "local"
    run = run_study(load_study(study_file), out, workers=2, progress=False)
    assert (run.computed, run.failed) == (16, 0)
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()
    assert (out / "points.parquet").read_bytes() == (serial / "points.parquet").read_bytes()


def _wait_for(predicate, timeout: float, what: str):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


@contextlib.contextmanager
def dask_cluster(folder: Path, workers: int, options: tuple = ()):
    """``dask scheduler`` and ``workers`` x ``dask worker`` processes on 127.0.0.1 (with
    ``options``, e.g. TLS files, on both); yields the scheduler's address."""
    dask = Path(sys.executable).with_name("dask")
    sched_file = folder / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    common = ["--host", "127.0.0.1", "--no-dashboard", *options]
    procs = [
        subprocess.Popen([dask, "scheduler", "--port", "0", "--scheduler-file", sched_file, *common], **quiet)
    ]
    try:
        _wait_for(sched_file.exists, 60, "the scheduler file")
        address = _wait_for(
            lambda: json.loads(sched_file.read_text() or "{}").get("address"), 30, "the address"
        )
        for _ in range(workers):
            procs.append(
                subprocess.Popen(
                    [dask, "worker", address, "--nthreads", "1", "--nworkers", "1", *common], **quiet
                )
            )
        yield address
    finally:
        for p in procs[::-1]:
            p.terminate()
        for p in procs:
            p.wait(30)


@pytest.mark.slow
def test_external_scheduler_and_workers_give_the_serial_bytes(study_file, serial, tmp_path):
    with dask_cluster(tmp_path, workers=2) as address:
        from distributed import Client

        with Client(address) as client:
            client.wait_for_workers(2, timeout=60)
        out = study_file.parent / "external"
        run = run_study(load_study(study_file), out, scheduler=address, progress=False)
    assert (run.computed, run.failed) == (16, 0)
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()


@pytest.mark.slow
def test_a_killed_worker_does_not_change_the_results(study_file, serial):
    killed = []

    def kill_one(client):
        if not killed:
            pids = sorted(client.run(os.getpid).values())
            os.kill(pids[0], signal.SIGKILL)
            killed.append(pids[0])

    out = study_file.parent / "killed"
    run = run_study(load_study(study_file), out, workers=2, progress=False, on_result=kill_one)
    assert killed, "no worker was killed"
    assert (run.computed, run.failed) == (16, 0)
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()


#: ``nlgrd study`` as the console script runs it, its fourth task held until SIGINT: the
#: interrupt always finds three tasks finished and thirteen to go (polling for task files
#: raced the 0.3 s tasks: under load all 16 could finish first, exit 0).
GATED_STUDY = """
import sys, time
from pathlib import Path
from nlgrd.cli.command import main
from nlgrd.studies import study_runner

real, started = study_runner.run_task, []

def gated(spec):
    if len(started) == 3:
        Path(sys.argv[1]).touch()  # three tasks written: the test may interrupt
        while True:
            time.sleep(60)  # SIGINT raises KeyboardInterrupt here
    started.append(spec.key)
    return real(spec)

study_runner.run_task = gated
raise SystemExit(main(sys.argv[2:]))
"""


@pytest.mark.slow
def test_an_interrupted_study_resumes_without_recomputing(study_file, serial, tmp_path):
    study = tmp_path / "s16.toml"
    shutil.copy(study_file, study)
    out = tmp_path / "out"
    gate = tmp_path / "gate"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    args = ["study", str(study), "--executor", "serial", "--out", str(out), "--no-progress"]
    p = subprocess.Popen(
        [sys.executable, "-c", GATED_STUDY, str(gate), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        _wait_for(lambda: gate.exists() or p.poll() is not None, 120, "three finished tasks")
        assert p.poll() is None, p.communicate()[1]
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert p.returncode == 130, err
    assert "rerun to resume" in err and "Traceback" not in err
    records = {f: f.read_bytes() for f in (out / "tasks").glob("*.json")}
    assert len(records) == 3
    assert not (out / "summary.csv").exists()
    rerun = subprocess.run([*NLGRD, *args], capture_output=True, text=True, env=env, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert "computed 13, skipped (finished before) 3" in rerun.stdout
    assert all(f.read_bytes() == b for f, b in records.items())
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()


@pytest.mark.slow
def test_embedded_cluster_listens_on_loopback_only():
    psutil = pytest.importorskip("psutil")
    from distributed import Client

    with local_cluster(2) as cluster, Client(cluster) as client:
        me = psutil.Process()
        procs = [me, *me.children(recursive=True)]
        worker_pids = set(client.run(os.getpid).values())
        assert worker_pids <= {p.pid for p in procs}
        listening = [
            (p.pid, s.laddr)
            for p in procs
            for s in p.net_connections(kind="inet")
            if s.status == psutil.CONN_LISTEN
        ]
        dashboard_port = int(cluster.dashboard_link.split(":")[2].split("/")[0])
    assert {pid for pid, _ in listening} >= worker_pids  # every worker listens somewhere
    assert dashboard_port in {a.port for _, a in listening}
    assert all(a.ip in ("127.0.0.1", "::1") for _, a in listening), listening


def test_a_task_that_raises_is_recorded_and_the_study_goes_on(tmp_path):
    """Each axis value alone is a valid model (checked at load); one combination is not:
    3000 N m on a 2e6 N/m mesh deflects it by 32 mm, more than the tooth depth. That task
    fails inside the study with the model check's message, the others finish, exit 1."""
    path = tmp_path / "bad.toml"
    path.write_text(
        STUDY.split("[[axes]]")[0].replace("[6000.0, 12000.0, 7]", "[6000.0, 12000.0, 2]")
        + '[[axes]]\nkey = "gear_pairs[0].torque"\nvalues = [107.83, 3000.0]\n'
        + '[[axes]]\nkey = "gear_pairs[0].mesh_stiffness"\nvalues = [0.2587e9, 2e6]\n'
    )
    r = subprocess.run(
        [*NLGRD, "study", str(path), "--executor", "serial", "--no-progress"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,  # the default output folder is in the current directory
    )
    assert r.returncode == 1, r.stderr
    assert "failed 1" in r.stdout and "Traceback" not in r.stderr
    summary = pd.read_csv(tmp_path / "bad" / "summary.csv")
    assert summary["status"].tolist() == ["done", "done", "done", "failed"]
    assert "gear_pairs[0].torque" in summary["error"][3] and "tooth depth" in summary["error"][3]


@pytest.mark.parametrize(
    "edit, key",
    [
        (('key = "gear_pairs[0].damping_ratio"', 'key = "gear_pairs[3].damping_ratio"'), "axes[1].values"),
        (("values = [50e-6,", "values = [-50e-6,"), "axes[0].values[0]"),
        (
            ('key = "gear_pairs[0].damping_ratio"', 'key = "gear_pairs[0].damping_ration"'),
            "axes[1].values[0]",
        ),
        (("range = [0.02, 0.08, 4]", "range = [0.02, 0.08]"), "axes[1].range"),
        (("harmonics = 5", "harmonics = 0"), "analysis.harmonics"),
        (('direction = "up"', 'direction = "sideways"'), "analysis.direction"),
        (("range = [0.02, 0.08, 4]", 'distribution = "normal"\nmean = 0.05\nstd = 0.01'), "sampling.samples"),
    ],
)
def test_a_bad_study_file_is_one_line_naming_file_and_key(tmp_path, edit, key):
    path = tmp_path / "s.toml"
    text = STUDY.replace(*edit)
    assert text != STUDY
    path.write_text(text)
    r = subprocess.run(
        [*NLGRD, "study", str(path), "--executor", "serial"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert r.returncode == 2
    line = r.stderr.strip()
    assert "\n" not in line and line.startswith(f"nlgrd: error: {path}: {key}"), line
    assert not (tmp_path / "s").exists()  # nothing ran


def test_latin_hypercube_draws_are_stratified_and_seeded(tmp_path):
    """McKay et al. (1979): with n draws, each of the n equal-probability strata of every
    sampled axis holds exactly one draw; the same seed gives the same draws."""
    from scipy import stats

    text = STUDY.replace("range = [0.02, 0.08, 4]", 'distribution = "normal"\nmean = 0.05\nstd = 0.01')
    text += '[sampling]\nmethod = "latin_hypercube"\nsamples = 10\nseed = 7\n'
    path = tmp_path / "lhs.toml"
    path.write_text(text)
    study = load_study(path)
    sets = study.parameter_sets()
    assert len(sets) == 4 * 10  # the grid axis times the draws (the same draws at each)
    d = [s["gear_pairs[0].damping_ratio [-]"] for s in sets]
    assert d[:10] == d[10:20]
    strata = sorted((stats.norm.cdf(d[:10], 0.05, 0.01) * 10).astype(int).tolist())
    assert strata == list(range(10))
    assert load_study(path).parameter_sets() == sets
    path.write_text(text.replace("seed = 7", "seed = 8"))
    assert load_study(path).parameter_sets() != sets


@pytest.mark.parametrize("name, tasks", [("kubo_jump_band", 16), ("kubo_relief_tolerance", 32)])
def test_shipped_study_files_are_valid(name, tasks):
    study = load_study(ROOT / "data" / "studies" / f"{name}.toml")
    assert len(study.parameter_sets()) == tasks


def test_study_figures_draw_the_summary(serial):
    """The map's cells are the summary's values (4 x 4, none missing); one curve per
    family value; the distribution's quantile lines sit at numpy's quantiles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nlgrd.plotting.studies import study_curves, study_distribution, study_map

    summary = pd.read_csv(serial / "summary.csv")
    b, z, q = "gear_pairs[0].geometry.backlash [m]", "gear_pairs[0].damping_ratio [-]", "dslr_peak [-]"
    ax = study_map(summary, z, b, q)
    cells = ax.collections[0].get_array()
    expected = summary.pivot_table(index=b, columns=z, values=q).to_numpy()
    assert cells.shape == (4, 4) and not np.ma.is_masked(cells)
    assert np.allclose(cells, expected, rtol=0, atol=0)
    ax = study_curves(summary, z, q, family=b)
    assert len(ax.lines) == 4
    ax = study_distribution(summary, q)
    lines = sorted(line.get_xdata()[0] for line in ax.lines)
    assert np.allclose(lines, np.quantile(summary[q], [0.05, 0.5, 0.95]))
    plt.close("all")


def test_profile_slope_tolerances_reach_the_lste_and_per_tooth_errors_their_period(tmp_path):
    """A tolerance axis on ``gear_pairs[0].errors.profile_slope_pinion`` changes the model's
    LSTE exactly as :func:`loaded_static_transmission_error` with the same
    :class:`GearErrors` does (same samples, to 1e-15 of the peak-to-peak); errors that
    differ from tooth to tooth give the model their period, a pinion revolution."""
    from nlgrd.gear.modifications import GearErrors
    from nlgrd.gear.transmission_error import loaded_static_transmission_error
    from nlgrd.io.model_file import model_from_file_data

    text = STUDY.replace("range = [0.02, 0.08, 4]", "values = [0.02]")
    text += '[[axes]]\nkey = "gear_pairs[0].errors.profile_slope_pinion"\ndistribution = "normal"\n'
    text += "mean = 0.0\nstd = 2e-6\n[sampling]\nsamples = 3\nseed = 1\n"
    path = tmp_path / "tol.toml"
    path.write_text(text)
    study = load_study(path)
    params = study.parameter_sets()[0]
    slope = params["gear_pairs[0].errors.profile_slope_pinion [m]"]
    assert slope != 0
    mesh = model_from_file_data(study.model_data(params), study.model_file).gear_pairs[0]
    direct = loaded_static_transmission_error(
        mesh.geometry, mesh.static_load, errors=GearErrors(profile_slope_pinion=slope), points_per_cycle=256
    )
    assert np.array_equal(mesh.lste_result().lste, direct.lste)
    bare = model_from_file_data(study.model, study.model_file).gear_pairs[0]
    assert abs(np.ptp(direct.lste) - np.ptp(bare.lste_result().lste)) > 1e-8  # the error changes the LSTE
    data = study.model_data(params)
    data["gear_pairs"][0]["errors"] = {"spacing_pinion": [1e-6] + [0.0] * 24}
    tooth = model_from_file_data(data, study.model_file).gear_pairs[0]
    assert tooth.error_period == 25  # swept over a pinion revolution (tests/test_shaft_orders.py)


def _self_signed(folder: Path) -> tuple[Path, Path]:
    """A self-signed certificate (its own CA) and its key, as PEM files, for 127.0.0.1."""
    import datetime
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import NameOID

    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "nlgrd-test")])
    now = datetime.datetime.now(datetime.UTC)
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=1))
        .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
        .add_extension(
            x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), False
        )
        .sign(key, hashes.SHA256())
    )
    cert_file, key_file = folder / "cert.pem", folder / "key.pem"
    cert_file.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    key_file.write_bytes(
        key.private_bytes(
            serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
        )
    )
    return cert_file, key_file


@pytest.mark.slow
def test_a_tls_cluster_is_used_with_the_dask_configuration_certificates(study_file, serial, tmp_path):
    """README: a ``dask scheduler`` and ``dask worker`` secured with TLS (one self-signed
    certificate as CA, server and client, as ``distributed.Security.temporary`` makes),
    and ``nlgrd study --scheduler tls://...`` taking the client's certificate from the Dask
    configuration (here its environment form): the study runs and gives the serial
    bytes. Without the configuration the address is refused before anything runs: exit
    status 2, one line naming --scheduler and the configuration keys to set."""
    cert, key = _self_signed(tmp_path)
    tls = ("--protocol", "tls", "--tls-ca-file", cert, "--tls-cert", cert, "--tls-key", key)
    with dask_cluster(tmp_path, workers=1, options=tls) as address:
        assert address.startswith("tls://127.0.0.1:")
        config = {
            "DASK_DISTRIBUTED__COMM__TLS__CA_FILE": str(cert),
            "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT": str(cert),
            "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY": str(key),
            "DASK_DISTRIBUTED__COMM__REQUIRE_ENCRYPTION": "True",
        }
        out = tmp_path / "tls"
        cmd = [*NLGRD, "study", str(study_file), "--scheduler", address, "--out", str(out), "--no-progress"]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env={**os.environ, **config})
        assert r.returncode == 0, r.stderr
        assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()
        bad = subprocess.run(
            [*cmd[:-3], "--out", str(tmp_path / "no"), "--no-progress"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        line = bad.stderr.strip()
        assert bad.returncode == 2 and "\n" not in line, bad.stderr
        assert line.startswith(f"nlgrd: error: --scheduler: {address} needs the client's TLS certificates")
        assert "distributed.comm.tls.ca-file" in line and not (tmp_path / "no").exists()
