"""What is wrong with a log file as a whole, said in one line each: cut off, corrupt, in the
file twice (:func:`file_damage`, from a reader's metadata), or its rows repeating another
file's (:func:`across_files`, for the inspection of several files)."""

from __future__ import annotations

from typing import Any

import pandas as pd

from rplearn.errors import InputError


def file_damage(path: str, info: dict[str, Any]) -> list[str]:
    """Lines saying a log file is cut off or corrupt (from its reader's metadata)."""
    lines = []
    if info.get("cut_off_at_byte") is not None:
        lines.append(
            f"{path}: the file is cut off inside the message at byte {info['cut_off_at_byte']:,}"
            + (f" ({info['cut_off_record']})" if info.get("cut_off_record") else "") + " "
            "(a log that ends early: power loss or an interrupted copy; that record is lost); "
            + (f"the {info['records_read']:,} complete record(s) before it were read"
               if info.get("records_read") is not None else "the complete records before it were read")
        )
    if info.get("corrupt"):
        at = f" (the first at byte {info['corrupt_at_byte']:,}: a message of no ULog type)" if info.get("corrupt_at_byte") else ""
        lines.append(f"{path}: corrupt bytes were skipped by the ULog reader (pyulog){at}; what follows them was read")
    if info.get("corrupt_bytes"):
        lines.append(f"{path}: {info['corrupt_bytes']:,} corrupt byte(s) between DataFlash records were skipped; "
                     "what follows them was read")
    if info.get("corrupt_frames"):
        lines.append(f"{path}: {info['corrupt_frames']:,} corrupt MAVLink frame(s) (bad checksum or framing) were "
                     "skipped: the messages in them are lost; what follows them was read")
    for what, by_file in (info.get("repeated_rows") or {}).items():
        for other, n in by_file.items():
            lines.append(f"{path}: {n:,} {what} row(s) repeat rows of {other} exactly (the same log given twice, "
                         "or overlapping exports); each was read once")
    if info.get("repeated_messages"):
        lines.append(f"{path}: {info['repeated_messages']:,} message(s) repeat an earlier one exactly (same receive "
                     "time and fields: part of the log is in the file twice); each was read once")
    return lines



def across_files(report: Any, poses: list[pd.DataFrame], canonical: list[pd.DataFrame],
                  signals: list[pd.DataFrame], owners: dict[str, list[int]]
                  ) -> tuple[list[pd.DataFrame], list[pd.DataFrame]]:
    """The logs of several files of an :class:`~rplearn.io.inspect.InspectReport` as ``read_logs`` takes them: rows repeating another file's
    read once and said, one stream given by two files over the same times said (``read_logs``
    refuses it). ``canonical``: the canonical pose log of each of ``poses`` (in file order)."""
    from rplearn.io.read import _drop_repeated_across, _refuse_overlaps

    if len(report.files) < 2:
        return poses, signals
    metas: list[dict[str, Any]] = [{"source": f["path"]} for f in report.files]
    once = _drop_repeated_across(canonical, owners["pose"], metas, "pose")
    for k, (before, after) in enumerate(zip(canonical, once, strict=True)):
        if len(after) < len(before):  # the file-order rows of those kept
            kept = pd.MultiIndex.from_frame(after[["t", "node"]].astype({"node": str}))
            poses[k] = poses[k][pd.MultiIndex.from_frame(poses[k][["t", "node"]].astype({"node": str})).isin(kept)]
    signals = _drop_repeated_across(signals, owners["signal"], metas, "signal")
    for f, meta in zip(report.files, metas, strict=True):
        if meta.get("repeated_rows"):
            f["repeated_rows"] = meta["repeated_rows"]
            report.problems.extend(line for line in file_damage(f["path"], meta))
    for what, logs in (("pose", once), ("signal", signals)):
        try:
            _refuse_overlaps(logs, owners[what], metas, what)
        except InputError as exc:
            report.problems.append(f"{exc} (sync refuses these files)")
    return poses, signals


__all__ = ["across_files", "file_damage"]
