"""The committed rocas/msgs/*_pb2.py must match proto/ (fails when someone forgets to regenerate)."""

import importlib
import subprocess
import sys
from pathlib import Path

import pytest
from google.protobuf import descriptor_pb2

ROOT = Path(__file__).resolve().parents[2]
PROTO = ROOT / "proto"


def test_every_proto_has_a_generated_module():
    protos = sorted(p.stem for p in (PROTO / "rocas" / "msgs").glob("*.proto"))
    generated = sorted(p.stem.removesuffix("_pb2") for p in (ROOT / "rocas" / "msgs").glob("*_pb2.py"))
    assert protos == generated


def test_generated_descriptors_match_the_proto_sources(tmp_path):
    pytest.importorskip("grpc_tools")
    out = tmp_path / "set.pb"
    files = sorted(str(p.relative_to(PROTO)) for p in PROTO.rglob("*.proto"))
    cmd = [sys.executable, "-m", "grpc_tools.protoc", f"-I{PROTO}",
           f"--descriptor_set_out={out}", *files]
    subprocess.run(cmd, check=True, capture_output=True)
    fresh = descriptor_pb2.FileDescriptorSet.FromString(out.read_bytes())
    for fd in fresh.file:
        module = importlib.import_module(fd.name.removesuffix(".proto").replace("/", ".") + "_pb2")
        committed = descriptor_pb2.FileDescriptorProto.FromString(module.DESCRIPTOR.serialized_pb)
        assert _schema(committed) == _schema(fd), f"{fd.name} is stale: run 'python proto/generate.py'"


def _schema(fd: descriptor_pb2.FileDescriptorProto) -> descriptor_pb2.FileDescriptorProto:
    """The schema without json_name (protoc fills it in only for descriptor sets)."""
    fd = descriptor_pb2.FileDescriptorProto.FromString(fd.SerializeToString())
    fd.ClearField("source_code_info")
    stack = list(fd.message_type)
    while stack:
        msg = stack.pop()
        for f in msg.field:
            f.ClearField("json_name")
        stack.extend(msg.nested_type)
    return fd
