"""How fast handdb builds a database, measured against the I/O floor (issue 8).

For synthetic inboxes of several sizes this prints, and saves as JSON in ``benchmarks/out/``:

- frames per second of every pipeline stage (ingest, bone lengths, gap fill, lift,
  validate, export, commit), timed by calling ``handdb.build.stages`` directly on the clips;
- the whole build (the Prefect flow, in a fresh process) against the I/O floor: pyarrow
  reading the same input CSVs and writing their rows as Parquet, nothing else; the fixed
  start-up cost (an empty build) is measured apart and subtracted;
- peak memory (``ru_maxrss``) of every build;
- how build time grows with clips and with frames (exponent of a log-log fit);
- Prefect's cost per task, from a flow of empty tasks shaped like the build;
- DuckDB query latencies on a database of ten million ``joints_3d`` rows;
- issue 16's targets, each with this run's figure and whether it is met: empty build,
  rebuild with nothing to do, ``handdb --help`` and ``handdb sql``, marginal build over
  the I/O floor, fixed cost per clip, peak memory.

Run: ``.venv/bin/python benchmarks/run.py [--plan quick|default|large] [--runner R]``
(``make bench``; ``--quick`` is a smoke test of every figure, not a measurement).
Figures by wall time are noisy on a shared machine; CPU seconds are printed beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq
from threadpoolctl import threadpool_limits

REPO = Path(__file__).resolve().parents[1]
OUT_DIR = REPO / "benchmarks" / "out"
PREFECT_HOME = OUT_DIR / "prefect-home"

#: Distinct synthetic clips per inbox; larger inboxes repeat them under other clip ids.
POOL_SIZE = 8
MOTIONS = ("rapid", "wave", "clench", "random")
#: Runs of hidden points per 1000 frames, so gap filling has work.
GAPS_PER_1000_FRAMES = 40
STAGES = ("ingest", "bone lengths", "gap fill", "lift", "validate", "export", "commit")
#: Rows of the synthetic ``joints_3d`` the queries run on.
QUERY_ROWS = 10_000_000
QUERY_CLIPS = 100
QUERY_REPEATS = 5
QUERIES = {
    "aggregate over joints_3d": (
        "SELECT lift_method, count(*) AS n, avg(z) AS mean_z, avg(scale) AS mean_scale "
        "FROM joints_3d GROUP BY lift_method"),
    "per-joint error": (
        "SELECT j.joint, avg(abs(j.z - t.z)) AS mean_abs_dz FROM joints_3d j "
        "JOIN truth_3d t USING (clip_id, frame, joint_index) GROUP BY j.joint ORDER BY j.joint"),
    "one clip's frames": "SELECT * FROM joints_3d WHERE clip_id = 'q-0042' ORDER BY frame",
}
PREFECT_OVERHEAD_CLIPS = 100
#: Where clips run in the measured builds, as ``handdb build --runner``.
DEFAULT_RUNNER = "thread"
#: The runner without Prefect (its builds skip the measure of Prefect's own cost).
LOCAL_RUNNER = "local"


@dataclass(frozen=True)
class Plan:
    """The inbox sizes a benchmark run builds: ``(n_clips, n_frames)`` pairs."""

    by_clips: tuple[tuple[int, int], ...]
    by_frames: tuple[tuple[int, int], ...]
    stage_clips: tuple[int, int]
    query_rows: int
    #: The inbox rebuilt with nothing to do (issue 16: 40 clips of 5000 frames).
    noop: tuple[int, int] = (40, 5000)
    #: Clips of the flow of empty tasks that measures Prefect alone.
    prefect_clips: int = PREFECT_OVERHEAD_CLIPS
    #: Runs of each start-up command (the median is reported).
    startup_repeats: int = 5


DEFAULT = Plan(by_clips=((10, 300), (30, 300), (100, 300)),
               by_frames=((4, 1000), (4, 5000), (4, 20_000)),
               stage_clips=(8, 5000), query_rows=QUERY_ROWS)
#: Every figure at small sizes (a few minutes): a smoke test, not a measurement.
QUICK = Plan(by_clips=((2, 100), (6, 100)), by_frames=((2, 200), (2, 800)),
             stage_clips=(2, 200), query_rows=100_000, noop=(4, 200), prefect_clips=10,
             startup_repeats=1)
LARGE = Plan(by_clips=((10, 300), (100, 300), (1000, 300)),
             by_frames=((10, 1000), (10, 5000), (10, 20_000)),
             stage_clips=(8, 20_000), query_rows=QUERY_ROWS)
PLANS = {"quick": QUICK, "default": DEFAULT, "large": LARGE}


# -- synthetic inboxes -------------------------------------------------------------------


def write_inbox(inbox: Path, n_clips: int, n_frames: int) -> int:
    """Write ``n_clips`` synthetic clips of ``n_frames`` (canonical CSV, truth, sidecar).

    ``POOL_SIZE`` distinct clips are synthesised (motions and seeds vary) and repeated
    under further clip ids. Returns the total number of frames.
    """
    from handdb.demo import hide_points
    from handdb.hand.skeletons import load_skeleton
    from handdb.ingest import get_format
    from handdb.synthetic import synthesize_clip

    inbox.mkdir(parents=True, exist_ok=True)
    tracks, truth = get_format("tracks_csv"), get_format("truth_csv")
    n_gaps = GAPS_PER_1000_FRAMES * n_frames // 1000
    for i in range(n_clips):
        clip_id = f"c{i:04d}"
        pool_id = f"c{i % POOL_SIZE:04d}"
        if i >= POOL_SIZE:
            for suffix in (".clip.json", tracks.suffix, ".truth.csv"):
                shutil.copyfile(inbox / f"{pool_id}{suffix}", inbox / f"{clip_id}{suffix}")
            continue
        clip = synthesize_clip(MOTIONS[i % len(MOTIONS)], n_frames, seed=i)
        skeleton = load_skeleton(clip.skeleton)
        rng = np.random.default_rng(i)
        uv = hide_points(clip.uv, n_gaps, rng)
        confidence = np.clip(rng.normal(0.9, 0.05, uv.shape[:2]), 0.0, 1.0)
        (inbox / f"{clip_id}.clip.json").write_text(json.dumps(clip.sidecar(subject=f"s{i}")))
        tracks.write(inbox / f"{clip_id}{tracks.suffix}", uv, confidence, skeleton)
        truth.write(inbox / f"{clip_id}.truth.csv", clip.xyz, skeleton)
    return n_clips * n_frames


# -- timing helpers ----------------------------------------------------------------------


@dataclass
class Timing:
    """Wall and CPU seconds of some work on ``frames`` frames."""

    wall: float = 0.0
    cpu: float = 0.0
    frames: int = 0

    @property
    def frames_per_second(self) -> float:
        """Frames per wall second."""
        return self.frames / self.wall if self.wall else float("nan")

    @property
    def frames_per_cpu_second(self) -> float:
        """Frames per CPU second (steadier than wall time on a shared machine)."""
        return self.frames / self.cpu if self.cpu else float("nan")


@contextmanager
def timed(timing: Timing, frames: int) -> Iterator[None]:
    """Add the wall and CPU time of the ``with`` block, and ``frames``, to ``timing``."""
    wall, cpu = time.perf_counter(), time.process_time()
    yield
    timing.wall += time.perf_counter() - wall
    timing.cpu += time.process_time() - cpu
    timing.frames += frames


def fitted_exponent(sizes: list[float], seconds: list[float]) -> float:
    """Slope of log(seconds) against log(size): 1 is linear growth."""
    return float(np.polyfit(np.log(sizes), np.log(seconds), 1)[0])


def load_average() -> float:
    """One-minute load average of the machine (other engineers share it)."""
    return os.getloadavg()[0]


# -- per-stage throughput ----------------------------------------------------------------


def stage_timings(inbox: Path, db: Path) -> dict[str, Timing]:
    """Time every pipeline stage on every clip of ``inbox``, calling the library directly.

    BLAS runs on one thread, as in a build (clips, not matrices, are what runs in parallel).
    """
    from handdb.build.plan import read_xray_inputs
    from handdb.ingest import discover
    from handdb.store.database import Store

    store = Store(str(db))
    ratios = read_xray_inputs([], store).ratios
    timings = {stage: Timing() for stage in STAGES}
    with threadpool_limits(limits=1, user_api="blas"):
        for entry in discover(inbox).clips:
            time_clip_stages(entry, inbox, store, ratios, timings)
    return timings


def time_clip_stages(entry: Any, inbox: Path, store: Any, ratios: pa.Table,
                     timings: dict[str, Timing]) -> None:
    """Run one clip through every stage, adding each stage's time to ``timings``."""
    from handdb.build import BuildOptions
    from handdb.build import stages as pipeline
    from handdb.build.keys import stage_keys
    from handdb.build.rows import clip_tables

    options = BuildOptions()
    keys = stage_keys(entry.clip_id, options, "", marker_clip=False)
    with timed(timings["ingest"], 0):
        result = pipeline.ClipResult(clip=pipeline.ingest(entry), keys=keys)
    n_frames = result.clip.n_frames
    timings["ingest"].frames += n_frames
    steps: dict[str, Callable] = {
        "bone lengths": lambda r: pipeline.resolve_bone_lengths(r, ratios),
        "gap fill": lambda r: pipeline.fill(r, options),
        "lift": lambda r: pipeline.lift_clip(r, options),
        "validate": lambda r: pipeline.validate(r, options),
        "export": lambda r: pipeline.export(r, store, options),
        "commit": lambda r: store.commit_clip(r.clip.clip_id, clip_tables(r, inbox)),
    }
    for stage, step in steps.items():
        with timed(timings[stage], n_frames):
            try:
                outcome = step(result)
            except pipeline.ClipRefused as refused:
                raise RuntimeError(f"benchmark clip {entry.clip_id} refused at {stage}: "
                                   f"{refused}") from refused
        result = outcome or result


# -- the I/O floor -----------------------------------------------------------------------


def io_floor(inbox: Path, out: Path) -> Timing:
    """pyarrow reads every input CSV and writes its rows as Parquet (zstd), nothing else."""
    out.mkdir(parents=True, exist_ok=True)
    timing = Timing()
    with timed(timing, 0):
        for path in sorted(inbox.glob("*.csv")):
            table = pa_csv.read_csv(path)
            pq.write_table(table, out / f"{path.name}.parquet", compression="zstd")
    return timing


# -- whole builds in a fresh process -----------------------------------------------------


def child_build(inbox: str, db: str, runner: str) -> None:
    """Run the build on ``runner`` and print its figures as JSON (the child side).

    CPU time counts the build's own worker processes (Dask's, a process pool's) as well.
    """
    start = time.perf_counter()
    from handdb.build import run_build

    imported = time.perf_counter()
    summary = run_build(inbox, db, runner=runner)
    finished = time.perf_counter()
    usage = resource.getrusage(resource.RUSAGE_SELF)
    workers = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(json.dumps({
        "import_seconds": imported - start,
        "flow_seconds": finished - imported,
        "process_seconds": finished - start,
        "cpu_seconds": usage.ru_utime + usage.ru_stime + workers.ru_utime + workers.ru_stime,
        "maxrss_mb": max(usage.ru_maxrss, workers.ru_maxrss) / 1024,
        "processed": len(summary.processed),
        "failed": len(summary.failed),
        "refused": len(summary.refusals),
    }))


def build(inbox: Path, db: Path, runner: str = DEFAULT_RUNNER) -> dict:
    """Build ``db`` from ``inbox`` in a fresh Python process; its figures and wall time."""
    env = os.environ | {"PREFECT_HOME": str(PREFECT_HOME)}
    start = time.perf_counter()
    done = subprocess.run([sys.executable, __file__, "--child-build", str(inbox), str(db),
                           runner],
                          capture_output=True, text=True, env=env, cwd=REPO, check=False)
    wall = time.perf_counter() - start
    if done.returncode:
        raise RuntimeError(f"build of {inbox} failed:\n{done.stderr[-3000:]}")
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    if figures["failed"] or figures["refused"]:
        raise RuntimeError(f"build of {inbox}: {figures}")
    return figures | {"wall_seconds": wall, "load": load_average()}


# -- Prefect's per-task cost -------------------------------------------------------------


def child_prefect_overhead(n_clips: int) -> None:
    """Print the seconds of a flow of empty tasks shaped like the build (the child side).

    One task per clip, kept in flight by the build's own sliding window and waited on
    through its own first-done helper, so the figure is what Prefect adds to each clip of
    a build.
    """
    from handdb_flows.build import WINDOW_PER_WORKER, first_done
    from handdb_flows.settings import quick_flows
    from prefect import flow, task
    from prefect.cache_policies import NO_CACHE
    from prefect.task_runners import ThreadPoolTaskRunner

    from handdb.build import DEFAULT_WORKERS
    from handdb.build.window import sliding_window

    @task(cache_policy=NO_CACHE)
    def process(clip: int) -> int:
        return clip

    @flow(task_runner=ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS))
    def clips(n: int) -> int:
        """Run ``n`` clips' tasks; how many completed."""
        window = DEFAULT_WORKERS * WINDOW_PER_WORKER
        finished = sliding_window(range(n), window, process.submit, first_done)
        return sum(future.state.is_completed() for _, future in finished)

    with quick_flows():
        clips(1)
        start = time.perf_counter()
        completed = clips(n_clips)
        seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds, "tasks": completed}))


def prefect_overhead(n_clips: int) -> dict:
    """Prefect's own time per clip of a build, from :func:`child_prefect_overhead`."""
    env = os.environ | {"PREFECT_HOME": str(PREFECT_HOME)}
    done = subprocess.run([sys.executable, __file__, "--child-overhead", str(n_clips)],
                          capture_output=True, text=True, env=env, cwd=REPO, check=True)
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    return figures | {"per_clip_ms": 1000 * figures["seconds"] / n_clips}


# -- queries -----------------------------------------------------------------------------


def write_query_database(db: Path, n_rows: int) -> int:
    """Write ``joints_3d`` and ``truth_3d`` of ``QUERY_CLIPS`` clips with synthetic values."""
    from handdb.hand.skeletons import load_skeleton
    from handdb.store import tables
    from handdb.store.database import Store

    store, skeleton = Store(str(db)), load_skeleton("mediapipe21")
    n_joints = skeleton.n_joints
    n_frames = n_rows // (QUERY_CLIPS * n_joints)
    rng = np.random.default_rng(0)
    frame = np.repeat(np.arange(n_frames, dtype=np.int32), n_joints)
    joint_index = np.tile(np.arange(n_joints, dtype=np.int32), n_frames)
    joint = pa.DictionaryArray.from_arrays(joint_index, skeleton.joints).cast(pa.string())
    n = frame.size
    for i in range(QUERY_CLIPS):
        clip_id = f"q-{i:04d}"
        xyz = rng.normal(0.0, 50.0, (n, 3))
        store.write("joints_3d", clip_id, tables.from_columns("joints_3d", {
            "clip_id": clip_id, "frame": frame, "joint": joint, "joint_index": joint_index,
            "u": xyz[:, 0] + 320, "v": xyz[:, 1] + 240, "observed": np.ones(n, bool),
            "confidence": np.full(n, 0.9), "filled": np.zeros(n, bool),
            "fill_method": pa.nulls(n, pa.string()), "x": xyz[:, 0], "y": xyz[:, 1],
            "z": xyz[:, 2], "lift_method": "default", "scale": np.ones(n),
            "sign_confidence": np.ones(n), "length_inconsistency": np.zeros(n),
            "residual": pa.nulls(n, pa.float64()), "flagged": np.zeros(n, bool),
        }))
        store.write("truth_3d", clip_id, tables.from_columns("truth_3d", {
            "clip_id": clip_id, "frame": frame, "joint": joint, "joint_index": joint_index,
            "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2] + rng.normal(0.0, 5.0, n),
        }))
    return QUERY_CLIPS * n


def query_latencies(db: Path) -> dict[str, float]:
    """Best of ``QUERY_REPEATS`` wall seconds of each query in :data:`QUERIES`."""
    from handdb.store.query import connect

    con = connect(str(db))
    latencies = {}
    for name, sql in QUERIES.items():
        best = float("inf")
        for _ in range(QUERY_REPEATS):
            start = time.perf_counter()
            con.sql(sql).to_arrow_table()
            best = min(best, time.perf_counter() - start)
        latencies[name] = best
    return latencies


# -- the run -----------------------------------------------------------------------------


def machine() -> dict:
    """What the figures were measured on."""
    cpu = next((line.split(":", 1)[1].strip() for line in
                Path("/proc/cpuinfo").read_text().splitlines() if line.startswith("model name")),
               platform.processor())
    mem_kb = next(int(line.split()[1]) for line in Path("/proc/meminfo").read_text().splitlines()
                  if line.startswith("MemTotal"))
    packages = ("numpy", "scipy", "pyarrow", "duckdb", "prefect", "usd-core", "matplotlib")
    return {"cpus": os.cpu_count(), "cpu_model": cpu, "memory_gb": round(mem_kb / 2**20, 1),
            "python": platform.python_version(),
            "packages": {name: metadata.version(name) for name in packages},
            "load_at_start": load_average()}


def print_stage_table(timings: dict[str, Timing]) -> None:
    total = Timing(sum(t.wall for t in timings.values()), sum(t.cpu for t in timings.values()),
                   next(iter(timings.values())).frames)
    print(f"{'stage':<14}{'frames':>9}{'wall s':>9}{'cpu s':>9}{'frames/s':>12}"
          f"{'frames/cpu s':>14}")
    for stage, timing in [*timings.items(), ("all stages", total)]:
        print(f"{stage:<14}{timing.frames:>9}{timing.wall:>9.2f}{timing.cpu:>9.2f}"
              f"{timing.frames_per_second:>12,.0f}{timing.frames_per_cpu_second:>14,.0f}")


def run_builds(sizes: tuple[tuple[int, int], ...], scratch: Path,
               startup: dict[str, float], runner: str) -> list[dict]:
    """Build an inbox of every size; time it against the I/O floor."""
    rows = []
    for n_clips, n_frames in sizes:
        inbox, db = scratch / f"inbox-{n_clips}x{n_frames}", scratch / f"db-{n_clips}x{n_frames}"
        frames = write_inbox(inbox, n_clips, n_frames)
        floor = io_floor(inbox, scratch / f"floor-{n_clips}x{n_frames}")
        figures = build(inbox, db, runner)
        beyond = figures["process_seconds"] - startup["process_seconds"]
        beyond_cpu = figures["cpu_seconds"] - startup["cpu_seconds"]
        rows.append(figures | {"n_clips": n_clips, "n_frames": n_frames, "frames": frames,
                               "floor_seconds": floor.wall, "floor_cpu_seconds": floor.cpu,
                               "beyond_startup": beyond, "beyond_startup_cpu": beyond_cpu,
                               "floor_ratio": beyond / floor.wall,
                               "floor_ratio_cpu": beyond_cpu / floor.cpu,
                               "build_frames_per_second": frames / beyond})
        shutil.rmtree(db)
        print(f"{n_clips:>6}{n_frames:>8}{frames:>10}{figures['process_seconds']:>9.1f}"
              f"{figures['cpu_seconds']:>8.1f}{beyond:>9.1f}{floor.wall:>8.2f}"
              f"{beyond / floor.wall:>8.1f}{beyond_cpu / floor.cpu:>10.1f}"
              f"{frames / beyond:>10,.0f}{figures['maxrss_mb']:>9.0f}{figures['load']:>6.1f}",
              flush=True)
    return rows


# -- issue 16's targets ------------------------------------------------------------------


def startup_commands(scratch: Path, repeats: int) -> dict[str, float]:
    """Median wall seconds of ``handdb --help`` and ``handdb sql "SELECT 1"``, fresh processes."""
    sys.path.insert(0, str(REPO))
    from benchmarks.bench_startup import small_database, wall_time

    cli = [sys.executable, "-c", "from handdb.cli import main; main()"]
    db = small_database(scratch / "startup")
    return {"help": wall_time([*cli, "--help"], repeats),
            "sql": wall_time([*cli, "sql", "SELECT 1", "--db", str(db)], repeats)}


def noop_rebuild(scratch: Path, n_clips: int, n_frames: int, runner: str) -> dict:
    """Build an inbox, then build it again with nothing changed; the second build's figures."""
    inbox, db = scratch / f"noop-inbox-{n_clips}x{n_frames}", scratch / "noop-db"
    write_inbox(inbox, n_clips, n_frames)
    build(inbox, db, runner)
    return build(inbox, db, runner) | {"n_clips": n_clips, "n_frames": n_frames}


def slope(rows: list[dict], size: str, value: str) -> float:
    """Change of ``value`` per unit of ``size`` between the first and last of ``rows``."""
    first, last = rows[0], rows[-1]
    return (last[value] - first[value]) / (last[size] - first[size])


@dataclass(frozen=True)
class Target:
    """One line of the targets table: a figure, how it reads, issue 16's bound."""

    figure: str
    value: float
    shown: str
    target: str
    met: bool
    load: float


def targets(results: dict) -> list[Target]:
    """Issue 16's targets, each with this run's figure (ratios within this one run).

    The marginal build and the fixed cost per clip are differences between builds, so the
    start-up cancels: the marginal ratio is the longest clips' build beyond an empty one,
    over the I/O floor of the same files; the fixed cost per clip is the build's CPU per
    added clip (``by_clips``) less the per-frame CPU (``by_frames``) times those clips'
    frames. Peak RSS is bounded if it does not grow with the number of clips.
    """
    startup, noop, commands = results["startup"], results["noop"], results["commands"]
    by_clips, by_frames = results["by_clips"], results["by_frames"]
    longest, many, few = by_frames[-1], by_clips[-1], by_clips[0]
    per_frame_cpu = slope(by_frames, "frames", "cpu_seconds")
    fixed_cpu = slope(by_clips, "n_clips", "cpu_seconds") - per_frame_cpu * many["n_frames"]
    rss_growth = many["maxrss_mb"] / few["maxrss_mb"]
    shape = f"{longest['n_clips']} x {longest['n_frames']}"
    return [
        Target("empty build, wall", startup["wall_seconds"], f"{startup['wall_seconds']:.2f} s",
               "<= 5 s", startup["wall_seconds"] <= 5, startup["load"]),
        Target(f"rebuild with nothing to do, {noop['n_clips']} x {noop['n_frames']}, wall",
               noop["wall_seconds"], f"{noop['wall_seconds']:.2f} s", "<= 2 s",
               noop["wall_seconds"] <= 2, noop["load"]),
        Target("handdb --help, wall", commands["help"], f"{commands['help']:.2f} s", "< 1 s",
               commands["help"] < 1, commands["load"]),
        Target('handdb sql "SELECT 1", wall', commands["sql"], f"{commands['sql']:.2f} s",
               "< 1 s", commands["sql"] < 1, commands["load"]),
        Target(f"marginal build / I/O floor, {shape}, CPU", longest["floor_ratio_cpu"],
               f"{longest['floor_ratio_cpu']:.1f}x", "<= 3x", longest["floor_ratio_cpu"] <= 3,
               longest["load"]),
        Target(f"marginal build / I/O floor, {shape}, wall", longest["floor_ratio"],
               f"{longest['floor_ratio']:.1f}x", "<= 3x", longest["floor_ratio"] <= 3,
               longest["load"]),
        Target(f"fixed cost per clip, {few['n_clips']}..{many['n_clips']} x "
               f"{many['n_frames']}, CPU", 1000 * fixed_cpu, f"{1000 * fixed_cpu:.0f} ms",
               "<= 50 ms", fixed_cpu <= 0.05, many["load"]),
        Target(f"peak RSS, {many['n_clips']} against {few['n_clips']} clips", rss_growth,
               f"{many['maxrss_mb']:.0f} MB ({rss_growth:.2f}x)",
               "bounded by the clips in flight (<= 1.25x)", rss_growth <= 1.25, many["load"]),
    ]


def print_targets(rows: list[Target]) -> None:
    """The targets as a markdown table."""
    print("| figure | this run | target | met? | load |\n|---|---:|---|---|---:|")
    for row in rows:
        print(f"| {row.figure} | {row.shown} | {row.target} | {'yes' if row.met else 'no'} "
              f"| {row.load:.1f} |")


def main(plan: Plan, out: Path, runner: str = DEFAULT_RUNNER) -> dict:
    results: dict = {"machine": machine(), "plan": asdict(plan), "runner": runner}
    print(f"{results['machine']['cpu_model']}, {results['machine']['cpus']} CPUs, "
          f"load {results['machine']['load_at_start']:.1f}")
    PREFECT_HOME.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="handdb-bench-") as folder:
        scratch = Path(folder)
        empty = scratch / "empty-inbox"
        empty.mkdir()
        build(empty, scratch / "warm-up-db", runner)
        startups = [build(empty, scratch / f"empty-db-{i}", runner) for i in range(3)]
        startup = {name: min(s[name] for s in startups) for name in
                   ("process_seconds", "cpu_seconds", "import_seconds", "flow_seconds",
                    "maxrss_mb", "wall_seconds")} | {"load": load_average()}
        results["startup"] = startup
        print(f"start-up (empty build in a fresh process): {startup['process_seconds']:.1f} s, "
              f"{startup['cpu_seconds']:.1f} s CPU "
              f"(imports {startup['import_seconds']:.1f} s), {startup['maxrss_mb']:.0f} MB")

        n_clips, n_frames = plan.stage_clips
        stage_inbox = scratch / "stage-inbox"
        write_inbox(stage_inbox, n_clips, n_frames)
        timings = stage_timings(stage_inbox, scratch / "stage-db")
        results["stages"] = {"n_clips": n_clips, "n_frames": n_frames,
                             **{s: asdict(t) | {"frames_per_second": t.frames_per_second,
                                                  "frames_per_cpu_second": t.frames_per_cpu_second}
                                for s, t in timings.items()}}
        print(f"\nstages, called directly on {n_clips} clips of {n_frames} frames "
              f"(load {load_average():.1f}):")
        print_stage_table(timings)

        print(f"\nwhole builds in a fresh process; 'beyond' is the build's time less start-up\n"
              f"{'clips':>6}{'frames':>8}{'total':>10}{'build s':>9}{'cpu s':>8}{'beyond':>9}"
              f"{'floor':>8}{'ratio':>8}{'cpu ratio':>10}{'frames/s':>10}{'RSS MB':>9}{'load':>6}")
        results["by_clips"] = run_builds(plan.by_clips, scratch, startup, runner)
        results["by_frames"] = run_builds(plan.by_frames, scratch, startup, runner)
        results["growth"] = {
            "clips_exponent": fitted_exponent([r["n_clips"] for r in results["by_clips"]],
                                              [r["beyond_startup"] for r in results["by_clips"]]),
            "frames_exponent": fitted_exponent(
                [r["n_frames"] for r in results["by_frames"]],
                [r["beyond_startup"] for r in results["by_frames"]]),
        }
        print(f"growth: time ~ clips^{results['growth']['clips_exponent']:.2f}, "
              f"time ~ frames^{results['growth']['frames_exponent']:.2f}")

        if runner != LOCAL_RUNNER:
            overhead = prefect_overhead(plan.prefect_clips)
            results["prefect_overhead"] = overhead
            print(f"Prefect alone: {overhead['per_clip_ms']:.1f} ms per clip "
                  "(one task each, as the build)")

        query_db = scratch / "query-db"
        n_rows = write_query_database(query_db, plan.query_rows)
        latencies = query_latencies(query_db)
        results["queries"] = {"joints_3d_rows": n_rows, "seconds": latencies}
        print(f"\nDuckDB on {n_rows:,} joints_3d rows (best of {QUERY_REPEATS}):")
        for name, seconds in latencies.items():
            print(f"  {name:<26}{1000 * seconds:>9.0f} ms")

        results["noop"] = noop_rebuild(scratch, *plan.noop, runner)
        results["commands"] = startup_commands(scratch, plan.startup_repeats) | {
            "load": load_average()}
        rows = targets(results)
        results["targets"] = [asdict(row) for row in rows]
        print(f"\nissue 16's targets (builds on the '{runner}' runner):")
        print_targets(rows)
    results["load_at_end"] = load_average()
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=1))
    print(f"\nfigures: {out}")
    return results


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plan", choices=PLANS, default="default",
                        help="inbox sizes: quick (minutes), default (10-15 min on 2 busy cores), "
                             "large (1000 clips; an hour or more)")
    parser.add_argument("--quick", action="store_const", const="quick", dest="plan",
                        help="same as --plan quick")
    parser.add_argument("--out", type=Path, help="JSON file of the figures")
    parser.add_argument("--runner", default=DEFAULT_RUNNER,
                        help="where the measured builds run clips (handdb build --runner)")
    parser.add_argument("--child-build", nargs=3, metavar=("INBOX", "DB", "RUNNER"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--child-overhead", type=int, metavar="CLIPS", help=argparse.SUPPRESS)
    return parser.parse_args()


if __name__ == "__main__":
    args = parse_args()
    if args.child_build:
        child_build(*args.child_build)
    elif args.child_overhead:
        child_prefect_overhead(args.child_overhead)
    else:
        main(PLANS[args.plan], args.out or OUT_DIR / f"bench-{args.plan}.json", args.runner)
