"""Names from data as path components (rocas._fs.safe_component, inside)."""

import pytest

from rocas._fs import inside, is_safe_component, safe_component
from rocas.errors import InputError


@pytest.mark.parametrize("name,expected", [
    ("a01_creeping_car_junction", "a01_creeping_car_junction"),
    ("A-1.2", "A-1.2"),
    ("../../etc/passwd", "etc_passwd"),
    ("/abs/path", "abs_path"),
    ("a/../../b", "a_b"),
    ("..", "unnamed"), (".", "unnamed"), ("", "unnamed"),
    (".hidden", "hidden"),
    ("x\r\x1b[2Ky", "x_2Ky"),
    ("C:\\Windows", "C_Windows"),
    ("x" * 300, "x" * 120),
])
def test_a_name_becomes_one_harmless_component(name, expected):
    out = safe_component(name)
    assert out == expected
    assert "/" not in out and "\\" not in out and ".." not in out and not out.startswith(".")
    assert is_safe_component(out) and safe_component(out) == out


def test_unsafe_names_are_told_apart():
    assert is_safe_component("a07_rear_ended_at_red")
    for bad in ("../x", "/x", "..", "", "a b", None, 3):
        assert not is_safe_component(bad)


def test_inside_refuses_what_leads_out(tmp_path):
    (tmp_path / "runs").mkdir()
    assert inside(tmp_path, "runs", "a") == (tmp_path / "runs" / "a").resolve()
    for parts in (("..", "x"), ("/etc/passwd",), ("runs", "../../x")):
        with pytest.raises(InputError, match="leads outside"):
            inside(tmp_path, *parts)
    (tmp_path / "runs" / "link").symlink_to("/tmp")
    with pytest.raises(InputError, match="leads outside"):
        inside(tmp_path, "runs", "link", "x")
