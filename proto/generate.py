"""Regenerate the Python modules in rocas/msgs/ from the .proto sources in proto/.

Run from anywhere: ``python proto/generate.py``. Needs grpcio-tools (a dev extra).
tests/msgs/test_generated.py fails when the committed modules are stale.
"""

from __future__ import annotations

import sys
from pathlib import Path

PROTO_ROOT = Path(__file__).resolve().parent
REPO_ROOT = PROTO_ROOT.parent


def proto_files() -> list[Path]:
    """The .proto sources, sorted, as paths relative to proto/."""
    return sorted(p.relative_to(PROTO_ROOT) for p in PROTO_ROOT.rglob("*.proto"))


def generate(out_dir: Path = REPO_ROOT) -> None:
    """Compile every .proto under proto/ into ``out_dir`` (python + type stubs)."""
    from grpc_tools import protoc

    args = ["protoc", f"-I{PROTO_ROOT}", f"--python_out={out_dir}", f"--pyi_out={out_dir}"]
    args += [str(p) for p in proto_files()]
    if protoc.main(args) != 0:
        raise SystemExit("protoc failed")


if __name__ == "__main__":
    generate(Path(sys.argv[1]) if len(sys.argv) > 1 else REPO_ROOT)
