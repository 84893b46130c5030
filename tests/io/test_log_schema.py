"""What the MAVLink/DataFlash readers rely on (rplearn.io._log_schema): fields read as numbers
naming message, field and file; library printing kept off both file descriptors."""

from __future__ import annotations

import ctypes
import os
import sys

import pytest

from rplearn.errors import LogFormatError
from rplearn.io._log_schema import dataflash_time_field, library_quiet, number


class _Fmt:
    def __init__(self, columns):
        self.columns = columns


class _Msg:
    def __init__(self, columns, **values):
        self.fmt = _Fmt(columns)
        self._values = values

    def get_fieldnames(self):
        return self.fmt.columns

    def __getattr__(self, name):
        values = self.__dict__["_values"]
        if name not in values:
            raise AttributeError(name)
        if values[name] == "abc":
            raise ValueError("invalid literal for int() with base 10: 'abc'")
        return values[name]


def test_fields_are_numbers_or_a_line_naming_message_field_and_file():
    msg = _Msg(["TimeUS", "RSSI"], TimeUS=5, RSSI="abc")
    assert number(msg, "RAD", "TimeUS", "f.bin") == 5.0
    with pytest.raises(LogFormatError, match=r"^f\.bin: RAD field RSSI is not a number \(invalid literal .*'abc'\)$"):
        number(msg, "RAD", "RSSI", "f.bin")
    with pytest.raises(LogFormatError, match="f.bin: a RAD message has no Noise field"):
        number(msg, "RAD", "Noise", "f.bin")
    assert number(msg, "RAD", "Noise", "f.bin", default=-1.0) == -1.0


def test_a_message_type_is_checked_against_its_fmt_once():
    assert dataflash_time_field(_Msg(["TimeMS", "Roll", "Pitch", "Yaw"]), "ATT", "f.log") == ("TimeMS", 1e-3)
    with pytest.raises(LogFormatError, match="f.log: ATT messages have no Yaw field"):
        dataflash_time_field(_Msg(["TimeUS", "Roll", "Pitch"]), "ATT", "f.log")
    with pytest.raises(LogFormatError, match="f.log: RAD messages have no TimeUS"):
        dataflash_time_field(_Msg(["RSSI"]), "RAD", "f.log")


def test_library_printing_never_reaches_the_terminal(capfd):
    libc = ctypes.CDLL(None)
    with library_quiet():
        print("python noise")
        print("python error noise", file=sys.stderr)
        libc.printf(b"c noise\n")
        os.write(2, b"fd noise\n")
    print("after")
    out, err = capfd.readouterr()
    assert "noise" not in out + err and out == "after\n"
