"""Result files are written atomically with the user's normal file mode."""
import os

from klaw_ocp.io.writers import atomic_write_bytes, atomic_write_text


def test_files_get_the_users_normal_mode_and_no_temporary_is_left(tmp_path):
    old = os.umask(0o022)
    try:
        atomic_write_text(tmp_path / "a" / "x.csv", "t,w\n0,1\n")
        atomic_write_bytes(tmp_path / "a" / "y.png", b"\x89PNG")
    finally:
        os.umask(old)
    assert (tmp_path / "a" / "x.csv").read_text() == "t,w\n0,1\n"
    assert (tmp_path / "a" / "y.png").read_bytes() == b"\x89PNG"
    assert {oct(p.stat().st_mode & 0o777) for p in (tmp_path / "a").iterdir()} == {"0o644"}
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["x.csv", "y.png"]
