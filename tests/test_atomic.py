"""rplearn._atomic: every output is written whole or not at all, never over an input."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from rplearn._atomic import atomic_open, atomic_path, check_output
from rplearn.errors import InputError


def leftovers(folder) -> list[str]:
    return sorted(n for n in os.listdir(folder) if n.startswith(".rplearn-"))


def test_a_successful_write_replaces_the_file_with_normal_permissions(tmp_path):
    target = tmp_path / "out.csv"
    with atomic_open(target) as fh:
        fh.write("a,b\n1,2\n")
    assert target.read_text() == "a,b\n1,2\n" and leftovers(tmp_path) == []
    assert os.stat(target).st_mode & 0o777 == 0o666 & ~_umask()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def test_a_failed_write_keeps_the_previous_file_and_leaves_nothing(tmp_path):
    target = tmp_path / "model.json"
    target.write_text("previous")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            with open(tmp, "w") as fh:
                fh.write("half a fil")
            raise RuntimeError("disk went away")
    assert target.read_text() == "previous" and leftovers(tmp_path) == []


def test_the_temporary_name_keeps_the_extension(tmp_path):
    with atomic_path(tmp_path / "t.csv.gz") as tmp:
        assert tmp.endswith("t.csv.gz") and os.path.dirname(tmp) == str(tmp_path)
        open(tmp, "w").close()


def test_outputs_that_are_inputs_folders_devices_or_in_missing_folders_are_refused(tmp_path):
    data = tmp_path / "d.csv"
    data.write_text("x\n")
    link = tmp_path / "alias.csv"
    link.symlink_to(data)
    for path, inputs, needle in [
        (data, [data], "is also an input"),
        (link, [data], "is also an input"),
        (tmp_path, [], "is a directory"),
        ("/dev/null", [], "not a regular file"),
        (tmp_path / "no" / "x.csv", [], "non-existent directory"),
    ]:
        with pytest.raises(InputError, match=needle):
            check_output(path, inputs)
    assert data.read_text() == "x\n"
    assert check_output(tmp_path / "new.csv", [data]) == str(tmp_path / "new.csv")


def test_a_full_disk_keeps_the_previous_file(tmp_path):
    """A write past the file-size limit (as on a full disk) fails cleanly: old file, no temp."""
    target = tmp_path / "big.csv"
    target.write_text("previous\n")
    script = textwrap.dedent(
        f"""
        import resource, signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
        from rplearn._atomic import atomic_open
        with atomic_open({str(target)!r}) as fh:
            fh.write("x" * 100_000)
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode != 0 and "File too large" in proc.stderr
    assert target.read_text() == "previous\n" and leftovers(tmp_path) == []


def test_a_run_stopped_mid_write_by_sigterm_keeps_the_previous_file(tmp_path):
    """The command line turns SIGTERM into an exit, so the file being written is removed."""
    target = tmp_path / "model.json"
    target.write_text("previous")
    script = textwrap.dedent(
        f"""
        import os, signal
        from rplearn._atomic import atomic_open
        from rplearn.cli._app import exit_on_sigterm
        exit_on_sigterm()
        with atomic_open({str(target)!r}) as fh:
            fh.write("half of a new model")
            fh.flush()
            os.kill(os.getpid(), signal.SIGTERM)
            fh.write("never written")
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == 143, proc.stderr
    assert target.read_text() == "previous" and leftovers(tmp_path) == []
