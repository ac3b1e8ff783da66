"""Benchmark of `rocas diff` (prints figures; not a test).

1. Whole processes on the shipped demo pair (recordings/demo): ``rocas diff A B --json``
   against a plain read + decode of both files (:data:`BASELINE`: mcap + mcap-protobuf-support,
   one DecoderFactory per file), each run ``--repeat`` times alternately; min and median of
   wall and CPU time (user + system, which a shared machine disturbs less), the ratios, and
   each child's peak RSS (target: diff <= 1.5x the baseline).
2. Generated pairs of the built-in channel mix at realistic rates and sizes
   (rocas.recording.synthetic: 100 Hz pose/chassis/control, 10 Hz perception/prediction/
   planning with 30 obstacles and 80-point forecasts, ~1 MB/s of serialized messages): the
   same whole-process comparison on the 30 s pair, and peak memory for 1x and 10x the length
   (target: flat, since both files are streamed).
3. The change-point solver: rocas's numpy PELT (``pelt_l2``) against
   ``ruptures.KernelCPD(kernel="linear")`` (the same change points, checked) and
   ``ruptures.Pelt(model="l2")`` on noisy step series of 300 and 1200 bins.

Bytecode: every child runs with its modules' bytecode cached, as for an installed package
(pip compiles a package's bytecode when it installs it): in a temporary
``PYTHONPYCACHEPREFIX``, filled by one untimed run of each command. Without that, a machine
that sets ``PYTHONDONTWRITEBYTECODE`` (as the project's sessions do) compiles rocas from
source in every ``rocas diff`` (about 0.07 s of CPU), while the baseline's libraries come
with their bytecode. ``--cold`` runs the children in the environment as it is.

``--before PYTHON`` also times ``PYTHON -m rocas diff`` (another checkout's interpreter, e.g.
main's venv) on the demo pair, alternated with the two others, and checks its JSON output is
this one's.

Usage: python tests/benchmarks/bench_diff.py [--repeat 5] [--long-factor 10] [--cold]
       [--before PYTHON]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mcap.reader import make_reader

from rocas.recording.synthetic import MixConfig, write_mix_pair

DEMO = Path(__file__).resolve().parents[2] / "recordings" / "demo"

#: The baseline: read and decode every protobuf message of the files named on the command
#: line (a small JSON status channel of bench_large's pair is left out, as mcap has no decoder
#: for it).
BASELINE = """
import sys
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
n = 0
for path in sys.argv[1:]:
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        topics = [c.topic for c in reader.get_summary().channels.values()
                  if c.message_encoding == "protobuf"]
        for _schema, _channel, _message, _decoded in reader.iter_decoded_messages(topics=topics):
            n += 1
print(n)
"""


def run_child(argv: list[str], env: dict[str, str] | None = None, cwd: str | None = None
              ) -> tuple[float, float, float, str]:
    """Run one child process to its end: (wall [s], CPU user + system [s], peak RSS [MB],
    stdout). Raises if it fails. The child's own resource usage comes from ``wait4``."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=err, env=env, cwd=cwd)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        out.seek(0)
        err.seek(0)
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(argv[:5])} ... failed ({proc.returncode}):\n"
                             f"{err.read().decode()[-2000:]}")
        return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, out.read().decode()


def bytecode_cached_env(prefix: str) -> dict[str, str]:
    """The environment with bytecode written to and read from ``prefix`` (module docstring)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = prefix
    return env


def compare_whole_processes(accident: str, reference: str, repeat: int, label: str,
                            target: float, env: dict[str, str] | None = None) -> str:
    """Print whole-process figures of ``rocas diff`` against :data:`BASELINE` on one pair and
    return the diff's JSON output (from its last run). The two alternate, so that a change of
    load on a shared machine touches both; with ``env`` (the children's environment), each
    runs once untimed first."""
    diff_argv = [sys.executable, "-m", "rocas", "diff", accident, reference, "--json"]
    base_argv = [sys.executable, "-c", BASELINE, accident, reference]
    runs: dict[str, list[tuple[float, float, float]]] = {"diff": [], "base": []}
    answer = ""
    if env is not None:
        run_child(base_argv, env=env)
        run_child(diff_argv, env=env)
    for _ in range(repeat):
        *figures, _ = run_child(base_argv, env=env)
        runs["base"].append(tuple(figures))  # type: ignore[arg-type]
        *figures, answer = run_child(diff_argv, env=env)
        runs["diff"].append(tuple(figures))  # type: ignore[arg-type]
    print(f"{label}: whole processes, {repeat} runs each")
    rows = {}
    for name, title in (("base", "read+decode (mcap-protobuf-support)"), ("diff", "rocas diff")):
        wall = [r[0] for r in runs[name]]
        cpu = [r[1] for r in runs[name]]
        rss = max(r[2] for r in runs[name])
        rows[name] = (min(wall), statistics.median(wall), min(cpu), statistics.median(cpu), rss)
        print(f"  {title:38s} wall min {min(wall):6.2f} s  median {statistics.median(wall):6.2f} s"
              f" | CPU min {min(cpu):6.2f} s  median {statistics.median(cpu):6.2f} s"
              f" | peak RSS {rss:5.0f} MB")
    b, d = rows["base"], rows["diff"]
    print(f"  ratio diff / read+decode: wall min {d[0] / b[0]:.2f}x, median {d[1] / b[1]:.2f}x; "
          f"CPU min {d[2] / b[2]:.2f}x, median {d[3] / b[3]:.2f}x  (target <= {target:g}x); "
          f"peak RSS {d[4] / b[4]:.2f}x")
    return answer


def compare_before_after(accident: str, reference: str, repeat: int, before_python: str,
                         env: dict[str, str] | None) -> None:
    """CPU of :data:`BASELINE`, ``before_python -m rocas diff`` and this ``rocas diff``, in
    turn ``repeat`` times (after one untimed run each), all from a neutral directory so that
    ``-m rocas`` finds each interpreter's own rocas."""
    here = str(Path(__file__).resolve().parents[2])
    cmds = {
        "read+decode": ([sys.executable, "-c", BASELINE, accident, reference], None),
        "before": ([before_python, "-m", "rocas", "diff", accident, reference, "--json"], None),
        "this": ([sys.executable, "-m", "rocas", "diff", accident, reference, "--json"], here),
    }
    cpu: dict[str, list[float]] = {k: [] for k in cmds}
    rss = dict.fromkeys(cmds, 0.0)
    out: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as neutral:
        for argv, path in cmds.values():
            run_child(argv, env=_with_path(env, path), cwd=neutral)
        for _ in range(repeat):
            for name, (argv, path) in cmds.items():
                _wall, used, peak_mb, out[name] = run_child(argv, env=_with_path(env, path),
                                                            cwd=neutral)
                cpu[name].append(used)
                rss[name] = max(rss[name], peak_mb)
    base = cpu["read+decode"]
    print(f"demo pair, before ({before_python}) and after: CPU, {repeat} runs each")
    for name, xs in cpu.items():
        ratio = "" if name == "read+decode" else (
            f"  ratio min {min(xs) / min(base):.2f}x, median "
            f"{statistics.median(xs) / statistics.median(base):.2f}x")
        print(f"  {name:12s} CPU min {min(xs):.3f} s  median {statistics.median(xs):.3f} s  "
              f"peak RSS {rss[name]:.0f} MB{ratio}")
    print(f"  same --json output before and after: {out['before'] == out['this']}")


def _with_path(env: dict[str, str] | None, path: str | None) -> dict[str, str] | None:
    """``env`` (or this environment) with ``path`` first on PYTHONPATH, if given."""
    if path is None:
        return env
    out = dict(os.environ if env is None else env)
    out["PYTHONPATH"] = os.pathsep.join(filter(None, [path, out.get("PYTHONPATH")]))
    return out


def raw_bytes(path: str) -> int:
    with open(path, "rb") as f:
        return sum(len(m.data) for _, _, m in make_reader(f).iter_messages())


def peak(acc: str, ref: str, env: dict[str, str] | None = None) -> tuple[float, float, str]:
    """(wall [s], peak RSS [MB], deviating module) of one whole-process ``rocas diff``."""
    wall, _cpu, rss, out = run_child([sys.executable, "-m", "rocas", "diff", acc, ref, "--json"],
                                     env=env)
    return wall, rss, json.loads(out)["deviating_module"]


def pelt_speedup(repeat: int) -> None:
    import numpy as np
    import ruptures

    from rocas.analysis.changepoints import pelt_l2

    for n in (300, 1200):
        rng = np.random.default_rng(0)
        y = (np.where(np.arange(n) >= n * 2 // 3, 1.0, 0.0) + 0.05 * rng.standard_normal(n))
        times = {}
        for name, solve in (
            ("rocas pelt_l2", lambda y=y: pelt_l2(y, 0.05, 2)),
            ("KernelCPD linear", lambda y=y: ruptures.KernelCPD(kernel="linear", min_size=2, jump=1)
             .fit(y.reshape(-1, 1)).predict(pen=0.05)),
            ("Pelt l2", lambda y=y: ruptures.Pelt(model="l2", min_size=2, jump=1)
             .fit(y.reshape(-1, 1)).predict(pen=0.05)),
        ):
            best = float("inf")
            for _ in range(repeat):
                t = time.perf_counter()
                ends = solve()
                best = min(best, time.perf_counter() - t)
            times[name] = (best, ends)
        (tr, er), (tk, ek), (tp, ep) = (times[k] for k in ("rocas pelt_l2", "KernelCPD linear",
                                                           "Pelt l2"))
        print(f"change points, {n} bins (min of {repeat}): rocas pelt_l2 {1000 * tr:.2f} ms, "
              f"KernelCPD linear {1000 * tk:.2f} ms, Pelt l2 {1000 * tp:.1f} ms; "
              f"same result: {er == ek == ep}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--long-factor", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cold", action="store_true",
                    help="run the children in this environment (no bytecode cache of their own)")
    ap.add_argument("--before", metavar="PYTHON",
                    help="also time PYTHON -m rocas diff on the demo pair (module docstring)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as pycache:
        run(args, None if args.cold else bytecode_cached_env(pycache))


def run(args: argparse.Namespace, env: dict[str, str] | None) -> None:
    print("children: " + ("this environment" if env is None else
                          "bytecode cached in a temporary PYTHONPYCACHEPREFIX"))
    acc, ref = str(DEMO / "a01_scripted_accident.mcap"), str(DEMO / "a01_scripted_reference.mcap")
    out = compare_whole_processes(acc, ref, args.repeat, "demo pair (recordings/demo)", 1.5, env)
    print(f"  deviating module: {json.loads(out)['deviating_module']}")
    if args.before:
        compare_before_after(acc, ref, args.repeat, args.before, env)
    with tempfile.TemporaryDirectory() as tmp:
        cfg = MixConfig(duration_s=30.0)
        t = time.perf_counter()
        acc, ref = write_mix_pair(tmp, cfg, "x1")
        gen_s = time.perf_counter() - t
        size = (os.path.getsize(acc) + os.path.getsize(ref)) / 1e6
        payload = (raw_bytes(acc) + raw_bytes(ref)) / 1e6
        print(f"30 s synthetic pair: {size:.1f} MB on disk (zstd), {payload:.1f} MB of serialized "
              f"messages; generated in {gen_s:.1f} s")
        compare_whole_processes(acc, ref, args.repeat, "30 s synthetic pair", 1.5, env)
        s1, m1, dev1 = peak(acc, ref, env)
        print(f"peak RSS  1x ({cfg.duration_s:.0f} s): {m1:.0f} MB  (diff {s1:.1f} s, {dev1})")
        long_cfg = MixConfig(duration_s=cfg.duration_s * args.long_factor,
                             deviate_at_s=cfg.duration_s * args.long_factor - 10)
        acc10, ref10 = write_mix_pair(tmp, long_cfg, "x10")
        s10, m10, dev10 = peak(acc10, ref10, env)
        print(f"peak RSS {args.long_factor}x ({long_cfg.duration_s:.0f} s): {m10:.0f} MB  "
              f"(diff {s10:.1f} s, {dev10}); ratio {m10 / m1:.2f}")
    pelt_speedup(args.repeat)


if __name__ == "__main__":
    main()
