"""Files written for a user are whole or absent (app/fileout.py): a full disk during a CLI export
leaves no 0-byte or partial file, an earlier file untouched, and a message naming the file."""

from __future__ import annotations

import errno
import os

import pytest

from paraspace.app import cli, fileout


def _full_disk(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every temporary file the writer opens behaves like a full disk (Linux's /dev/full: ENOSPC)."""
    real_fdopen = os.fdopen

    def fdopen(fd: int, *args, **kwargs):
        os.close(fd)
        return real_fdopen(os.open("/dev/full", os.O_WRONLY), *args, **kwargs)

    monkeypatch.setattr(fileout.os, "fdopen", fdopen)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux's /dev/full")
def test_cli_export_to_a_full_disk_leaves_nothing_half_written(tmp_path, monkeypatch, capsys) -> None:
    target = tmp_path / "shell.stl"
    _full_disk(monkeypatch)
    code = cli.main(["workspace", "--voxel", "8", "--export", str(target)])
    err = capsys.readouterr().err
    assert code == 2
    assert str(target) in err and "No space left on device" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == [], "no partial file and no temporary file is left"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux's /dev/full")
def test_a_failed_write_keeps_the_earlier_file(tmp_path, monkeypatch) -> None:
    target = tmp_path / "front.csv"
    target.write_text("earlier\n")
    _full_disk(monkeypatch)
    with pytest.raises(OSError) as exc:
        fileout.write_atomic(target, "x" * 100_000)
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(target)
    assert target.read_text() == "earlier\n" and sorted(p.name for p in tmp_path.iterdir()) == ["front.csv"]


def test_write_atomic_writes_text_and_bytes(tmp_path) -> None:
    fileout.write_atomic(tmp_path / "a.txt", "héllo\n")
    fileout.write_atomic(tmp_path / "b.bin", b"\x00\x01")
    assert (tmp_path / "a.txt").read_text(encoding="utf-8") == "héllo\n"
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.bin"]
