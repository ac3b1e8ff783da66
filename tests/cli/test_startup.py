"""Start-up cost: heavy libraries are imported where they are used, not to parse options."""

import subprocess
import sys

HEAVY = ("numpy", "networkx", "scipy", "ruptures", "rerun", "pymoo", "rosbags", "google.protobuf")
NOT_FOR_OPTIONS = ("scipy", "ruptures", "rerun", "pymoo", "rosbags")


def _imported(*argv: str) -> set[str]:
    code = "import sys; from rocas.cli.main import main; sys.exit(main(sys.argv[1:]))"
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code, *argv],
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    names = set()
    for line in done.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            names.add(line.rsplit("|", 1)[1].strip())
    return names


def _top(names: set[str], roots: tuple[str, ...]) -> set[str]:
    return {n for n in names if any(n == r or n.startswith(r + ".") for r in roots)}


def test_version_imports_nothing_heavy():
    assert _top(_imported("--version"), HEAVY) == set()


def test_diff_options_parse_without_the_analysis_libraries():
    assert _top(_imported("diff", "--help"), NOT_FOR_OPTIONS) == set()


def test_a_diff_imports_only_what_it_uses():
    """A whole diff needs neither ruptures (scipy.stats) nor the other commands' libraries."""
    from pathlib import Path

    demo = Path(__file__).resolve().parents[2] / "recordings" / "demo"
    names = _imported("diff", str(demo / "a01_scripted_accident.mcap"),
                      str(demo / "a01_scripted_reference.mcap"), "--json")
    assert "rocas.analysis.diff" in names
    assert _top(names, NOT_FOR_OPTIONS + ("rich", "rocas.search", "rocas.sim")) == set()
    # nor networkx (the CMG walk needs no graph library), numpy.ma (np.median's import) or
    # the recording writer
    assert _top(names, ("networkx", "numpy.ma", "rocas.recording.writer", "mcap.writer")) == set()
