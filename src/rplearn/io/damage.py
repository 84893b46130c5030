"""What is wrong with a log file as a whole, said in one line each: cut off, corrupt, in the
file twice (:func:`file_damage`, from a reader's metadata), or its rows repeating another
file's (:func:`drop_repeated_across`, :func:`refuse_overlaps`: what ``read_logs`` does with
several files; :func:`across_files`: the same said by the inspection of several files)."""

from __future__ import annotations

from typing import Any

import numpy as np
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
    if info.get("damaged_index"):
        d = info["damaged_index"]
        where = f" at byte {d['at_byte']:,} ({d['what']})" if d.get("at_byte") is not None else f" ({d['error']})"
        read = f" ({info['records_read']:,} message record(s) read)" if info.get("records_read") is not None else ""
        lost = ("; no message was lost" if info.get("cut_off_at_byte") is None and not info.get("damaged_chunks")
                else "")
        lines.append(f"{path}: the bag's index (from byte {d['index_pos']:,}) is damaged{where}: its messages were "
                     f"read record by record from the start{read}, as `rosbag reindex` does{lost}; "
                     "`rosbag reindex` rewrites the index")
    if info.get("unindexed"):
        lines.append(f"{path}: the bag has no index (its recorder never closed it): its messages were read record "
                     f"by record from the start" + (f" ({info['records_read']:,})" if info.get("records_read") else "")
                     + "; `rosbag reindex` writes the index")
    if info.get("corrupt"):
        at = f" (the first at byte {info['corrupt_at_byte']:,}: a message of no ULog type)" if info.get("corrupt_at_byte") else ""
        lines.append(f"{path}: corrupt bytes were skipped by the ULog reader (pyulog){at}; what follows them was read")
    for d in info.get("damaged_chunks") or []:
        lost = ("its messages after the damage are lost" if d.get("lost_messages") is None
                else f"its {d['lost_messages']:,} message(s) of the topics read are lost (damaged_chunk_messages)")
        lines.append(f"{path}: chunk {d['chunk']} of the bag (at byte {d['at_byte']:,}, {d['compression']}) is damaged "
                     f"({d['what']}: a flipped or overwritten byte): {lost}; the other chunks were read")
    if info.get("trailing_bytes"):
        lines.append(f"{path}: {info['trailing_bytes']:,} byte(s) after the bag's index were not read ("
                     + ("another bag begins there: a bag appended to this one, or this bag twice; read it on its own"
                        if info.get("trailing_bag") else "junk appended after the bag") + ")")
    if info.get("corrupt_stretches"):
        lines.append(f"{path}: {info['corrupt_stretches']:,} corrupt stretch(es) of MAVLink data "
                     f"({info.get('corrupt_bytes', 0):,} byte(s): bad checksum, broken framing or junk) were skipped: "
                     "the frames in them (one or more each) are lost; what follows them was read")
    elif info.get("corrupt_bytes"):
        lines.append(f"{path}: {info['corrupt_bytes']:,} corrupt byte(s) between DataFlash records were skipped; "
                     "what follows them was read")
    for what, by_file in (info.get("repeated_rows") or {}).items():
        for other, n in by_file.items():
            lines.append(f"{path}: {n:,} {what} row(s) repeat rows of {other} exactly (the same log given twice, "
                         "or overlapping exports); each was read once")
    if info.get("close_copies") and info.get("format") == "dataflash":
        lines.append(f"{path}: {info['close_copies']:,} DataFlash record(s) repeat one of their kind read shortly "
                     "before them (same fields, TimeUS the same or up to 1 ms later, far below the interval of records with "
                     "those fields: records written twice, by a logger or a router duplicating them, or a short stretch of the log "
                     "written again); each was read once")
    elif info.get("close_copies"):
        lines.append(f"{path}: {info['close_copies']:,} attitude or position message(s) repeat one received shortly "
                     "before them within 1 ms (same sender, boot time and fields: each message received twice, a router "
                     "or two links forwarding it); each was read once")
    if info.get("repeated_messages"):
        lines.append(f"{path}: {info['repeated_messages']:,} message(s) repeat an earlier one exactly (same receive "
                     "time and fields: part of the log is in the file twice); each was read once")
    lines += [f"{path}: {text}" for text in info.get("signal_row_problems") or ()]
    return lines


def signal_row_problems(signal: pd.DataFrame) -> list[str]:
    """What a signal table read forgivingly (:func:`rplearn.io.inspect.inspect_logs`) holds that
    ``sync`` cannot match, one line each: no rows; rows whose time, transmit power or carrier
    is not a finite number (``sync`` drops them: ``invalid_value``); rows whose transmitter is
    their receiver (``tx_equals_rx``)."""
    if signal.empty:
        return ["no signal rows (a header without samples)"]
    lines = []
    for col in ("t", "tx_power_dbm", "frequency_hz"):
        bad = ~np.isfinite(pd.to_numeric(signal[col], errors="coerce").to_numpy(np.float64))
        if bad.any():
            lines.append(f"column {col}: {int(bad.sum()):,} row(s) with a non-numeric, NaN or infinite value (first at "
                         f"row {int(np.flatnonzero(bad)[0])}); sync drops them (invalid_value)")
    same = (signal["tx"].astype(str) == signal["rx"].astype(str)).to_numpy()
    if same.any():
        lines.append(f"columns tx, rx: {int(same.sum()):,} row(s) from a node to itself (first at row "
                     f"{int(np.flatnonzero(same)[0])}); sync drops them (tx_equals_rx)")
    return lines

#: The columns that make two rows of different files one reading (the canonical ones: a
#: capture split in two numbers its frames anew).
_SAME_ROW = {"pose": ["t", "node", "x", "y", "z", "qw", "qx", "qy", "qz"],
             "signal": ["t", "tx", "rx", "rssi_dbm", "tx_power_dbm", "frequency_hz"]}
_STREAM = {"pose": ["node"], "signal": ["tx", "rx"]}


def drop_repeated_across(logs: list[pd.DataFrame], owners: list[int], files: list[dict[str, Any]],
                          what: str) -> list[pd.DataFrame]:
    """The logs without the rows that repeat a row of an earlier file exactly (the same log
    given twice under two names, overlapping exports), counted in that file's metadata
    (``repeated_rows``: ``{what: {earlier file: rows}}``). Repeats within one file are its
    reader's business and left alone. A file whose only such row is its ground station's one
    static row (two flights from one home, each log placing the station there at the first
    time of its boot clock: :func:`one_station`'s case) repeats no file: that row is read once
    and said as one station for both flights, not counted."""
    if len(set(owners)) < 2:
        return logs
    cols = _SAME_ROW[what]
    both = pd.concat([log[cols].assign(_file=i) for log, i in zip(logs, owners, strict=True)], ignore_index=True)
    key = both.groupby(cols, dropna=False, sort=False, observed=True).ngroup().to_numpy()
    earlier = both["_file"].groupby(key).transform("first").to_numpy()  # the file first giving each row
    repeat = earlier != both["_file"].to_numpy()
    out, start = [], 0
    for log, i in zip(logs, owners, strict=True):
        mine = repeat[start:start + len(log)]
        station = _lone_station_repeat(log, mine, files[i].get("station")) if what == "pose" else None
        if station is not None:
            first = str(files[int(earlier[start:start + len(log)][mine][0])].get("source"))
            files[i].setdefault("notes", []).append(
                f"{files[i].get('source')}: ground station {station} at the pose {first} gives it: one static station "
                "for both flights")
        elif mine.any():
            which, n_rows = np.unique(earlier[start:start + len(log)][mine].astype(np.int64), return_counts=True)
            counts = files[i].setdefault("repeated_rows", {}).setdefault(what, {})
            for j, n in zip(which.tolist(), n_rows.tolist(), strict=True):
                src = str(files[j].get("source", j))
                counts[src] = counts.get(src, 0) + int(n)
        if mine.any():
            log = log[~mine].reset_index(drop=True)
        out.append(log)
        start += len(mine)
    return out


def _lone_station_repeat(log: pd.DataFrame, repeat: np.ndarray, station: Any) -> str | None:
    """The station's node id when the one row of ``log`` repeating an earlier file's (``repeat``) is the station's
    one static row (its only row in ``log``), else None."""
    if station is None or np.count_nonzero(repeat) != 1:
        return None
    rows = log["node"].astype(str).to_numpy() == str(station)
    return str(station) if np.count_nonzero(rows) == 1 and bool(rows[repeat][0]) else None


def _station_at(row: pd.Series, meta: dict[str, Any]) -> str:
    """A station row's position [m] and where its reader placed it from."""
    note = meta.get("station_note")
    return f"({row['x']:.2f}, {row['y']:.2f}, {row['z']:.2f}) m" + (f" ({note})" if note else "")


def one_station(logs: list[pd.DataFrame], owners: list[int], files: list[dict[str, Any]]) -> list[pd.DataFrame]:
    """The pose logs with a ground station that several files place (MAVLink logs, ULogs read
    with their radio: each gives its ``station`` as one static row at its first time) given
    once: at the same pose, the earliest file's row is kept and the station is static across
    every file's flight (two rows at two times would make it a node logged over that span
    only, the later flights' samples out of its span); at different poses (a station moved
    between flights, two vehicles' homes) refused, naming both files and both positions: no
    pose between them is known, and a line between them is no place the station stood."""
    from rplearn.data.poses import SAME_POSITION_M

    given: dict[str, list[tuple[int, int, pd.Series]]] = {}
    for k, (log, i) in enumerate(zip(logs, owners, strict=True)):
        station = files[i].get("station")
        if station is None or not len(log):
            continue
        rows = log[log["node"].astype(str) == str(station)]
        if len(rows) == 1:
            given.setdefault(str(station), []).append((k, i, rows.iloc[0]))
    out = list(logs)
    for station, found in given.items():
        if len({i for _, i, _ in found}) < 2:
            continue
        found.sort(key=lambda f: float(f[2]["t"]))
        _, first_file, first = found[0]
        for k, i, row in found[1:]:
            a = first[["x", "y", "z"]].to_numpy(np.float64)
            b = row[["x", "y", "z"]].to_numpy(np.float64)
            qa, qb = (r[["qw", "qx", "qy", "qz"]].to_numpy(np.float64) for r in (first, row))
            same_q = min(np.max(np.abs(qa - qb)), np.max(np.abs(qa + qb))) <= SAME_QUATERNION
            frames = _frame(files[first_file]), _frame(files[i])
            noise = None
            if frames[0] is not None and frames[1] is not None:  # fixes of two logs compared in one frame only
                noise = fix_noise_m(files[first_file].get("station_accuracy_m"), files[i].get("station_accuracy_m"))
                b = _in_frame(b, frames[1], frames[0])
            apart = (float(np.hypot(*(a - b)[:2])), float(abs(a[2] - b[2])))
            moved = (bool(np.max(np.abs(a - b)) > SAME_POSITION_M) if noise is None
                     else apart[0] > noise[0] or apart[1] > noise[1])
            if moved or not same_q:
                turned = "" if moved else " (the same place, another heading)"
                said = ("" if not moved else ", two fixes of one station apart by GPS noise" if noise is None else
                        f" ({apart[0]:.2f} m across, {apart[1]:.2f} m up/down apart: more than the GPS noise the "
                        f"logs report for their fixes allows, {noise[0]:.2f} m and {noise[1]:.2f} m)")
                raise InputError(
                    f"{files[first_file].get('source')} and {files[i].get('source')} place the ground station "
                    f"{station} at {_station_at(first, files[first_file])} and at {_station_at(row, files[i])}, "
                    f"ENU{turned}: a station moved between flights{said}, or the homes of two vehicles; give where it "
                    "stood (ReaderOptions.station_geodetic: lat, lon, alt), or read each flight on its own",
                    param="station_geodetic")
            if row["t"] == first["t"] and not max(apart) > SAME_POSITION_M:
                continue  # the same row (a file given twice, or two flights from one home): drop_repeated_across's
            log = out[k]
            out[k] = log[~((log["node"].astype(str) == station) & (log["t"] == row["t"]))]
            within = (f" (its fixes {apart[0]:.2f} m across, {apart[1]:.2f} m up/down apart: within the GPS noise "
                      f"the logs report, {noise[0]:.2f} m and {noise[1]:.2f} m)"
                      if noise is not None and max(apart) > SAME_POSITION_M else "")
            files[i].setdefault("notes", []).append(
                f"{files[i].get('source')}: ground station {station} at the pose {files[first_file].get('source')} "
                f"gives it: one static station for both flights{within}")
    return out


#: Largest difference of the quaternion components of two rows of one static station (unitless)
#: for them to be one attitude.
SAME_QUATERNION = 1e-3
#: Two fixes of an unmoved station differ by up to this many standard deviations of their difference (the GPS
#: accuracies the logs report, ``station_accuracy_m``: a ULog's eph, epv, a MAVLink log's h_acc, v_acc or GPA HAcc, VAcc [m]) ...
FIX_SIGMAS = 3.0
#: ... and never by more than this [m]: a worse reported accuracy does not make a station moved farther one.
MAX_FIX_NOISE_M = 10.0


def _frame(meta: dict[str, Any]) -> tuple[float, ...] | None:
    """The geodetic origin of a file's ENU positions: the origin it was read around, else its log's own anchor
    (a ULog read without one), else None (unknown: an ENU table)."""
    frame = meta.get("origin_geodetic") or meta.get("anchor_geodetic")
    return None if frame is None else tuple(float(v) for v in frame)


def _in_frame(xyz: np.ndarray, frame: tuple[float, ...], to: tuple[float, ...]) -> np.ndarray:
    """ENU position ``xyz`` [m] around ``frame`` as ENU around ``to`` (both geodetic origins)."""
    if frame == to:
        return xyz
    from rplearn.core.geometry import enu_to_ned
    from rplearn.io.geodetic import geodetic_to_enu, local_ned_to_geodetic

    lat, lon, alt = local_ned_to_geodetic(enu_to_ned(xyz), frame)  # type: ignore[arg-type]
    return np.asarray(geodetic_to_enu(lat, lon, alt, to), np.float64).reshape(3)  # type: ignore[arg-type]


def fix_noise_m(a: Any, b: Any) -> tuple[float, float] | None:
    """How far apart [m] (across, up/down) two fixes of one unmoved station may lie, from the GPS accuracies
    (horizontal, vertical: standard deviations [m]) their logs report; None when either log reports none (then the
    positions must agree to :data:`~rplearn.data.poses.SAME_POSITION_M`)."""
    from rplearn.data.poses import SAME_POSITION_M

    try:
        sa, sb = np.asarray(a, np.float64).reshape(2), np.asarray(b, np.float64).reshape(2)
    except (TypeError, ValueError):
        return None
    if not (np.all(np.isfinite(sa)) and np.all(np.isfinite(sb)) and np.all(sa >= 0) and np.all(sb >= 0)):
        return None
    tol = np.clip(FIX_SIGMAS * np.hypot(sa, sb), SAME_POSITION_M, MAX_FIX_NOISE_M)
    return float(tol[0]), float(tol[1])


def refuse_overlaps(logs: list[pd.DataFrame], owners: list[int], files: list[dict[str, Any]], what: str) -> None:
    """Refuse two files giving one node's poses (one link's readings) over overlapping times
    with different rows: two logs of one stream, which would interleave."""
    spans: dict[tuple[str, ...], list[tuple[float, float, int, np.ndarray]]] = {}
    for log, i in zip(logs, owners, strict=True):
        if not len(log):
            continue
        for key, grp in log.groupby(_STREAM[what], sort=True, observed=True):
            t = np.sort(grp["t"].to_numpy(np.float64))
            spans.setdefault(tuple(str(k) for k in key), []).append((float(t[0]), float(t[-1]), i, t))
    for key, found in spans.items():
        for a in range(len(found)):
            for b in range(a + 1, len(found)):
                (a0, a1, fa, ta), (b0, b1, fb, tb) = found[a], found[b]
                lo, hi = max(a0, b0), min(a1, b1)
                inside = [int(np.count_nonzero((x >= lo) & (x <= hi))) for x in (ta, tb)]
                if fa != fb and hi > lo and min(inside) >= 2:
                    name = f"node {key[0]}'s poses" if what == "pose" else f"the readings of {key[0]} -> {key[1]}"
                    raise InputError(
                        f"{files[fa].get('source')} and {files[fb].get('source')} both give {name} from t = {lo:.3f} "
                        f"to {hi:.3f} s ({inside[0]:,} and {inside[1]:,} rows, not the same ones): two logs of one "
                        "stream would interleave; give one of them, or give them different node ids", param="paths")


def across_files(report: Any, poses: list[pd.DataFrame], canonical: list[pd.DataFrame],
                  signals: list[pd.DataFrame], owners: dict[str, list[int]]
                  ) -> tuple[list[pd.DataFrame], list[pd.DataFrame]]:
    """The logs of several files of an :class:`~rplearn.io.inspect.InspectReport` as ``read_logs`` takes them: rows repeating another file's
    read once and said, one stream given by two files over the same times said (``read_logs``
    refuses it). ``canonical``: the canonical pose log of each of ``poses`` (in file order)."""
    if len(report.files) < 2:
        return poses, signals
    metas: list[dict[str, Any]] = [{"source": f["path"], "station": f.get("station")} for f in report.files]
    once = drop_repeated_across(canonical, owners["pose"], metas, "pose")
    for k, (before, after) in enumerate(zip(canonical, once, strict=True)):
        if len(after) < len(before):  # the file-order rows of those kept
            kept = pd.MultiIndex.from_frame(after[["t", "node"]].astype({"node": str}))
            poses[k] = poses[k][pd.MultiIndex.from_frame(poses[k][["t", "node"]].astype({"node": str})).isin(kept)]
    signals = drop_repeated_across(signals, owners["signal"], metas, "signal")
    for f, meta in zip(report.files, metas, strict=True):
        if meta.get("repeated_rows"):
            f["repeated_rows"] = meta["repeated_rows"]
            report.problems.extend(file_damage(f["path"], meta))
    for what, logs in (("pose", once), ("signal", signals)):
        try:
            refuse_overlaps(logs, owners[what], metas, what)
        except InputError as exc:
            report.problems.append(f"{exc} (sync refuses these files)")
    stations = [{"source": f["path"], **{k: f.get(k) for k in ("station", "station_note", "station_accuracy_m",
                                                                 "origin_geodetic", "anchor_geodetic")}}
                for f in report.files]
    try:
        merged = one_station(canonical, owners["pose"], stations)
    except InputError as exc:
        report.problems.append(f"{exc} (sync refuses these files)")
        return poses, signals
    for k, (before, after) in enumerate(zip(canonical, merged, strict=True)):
        if len(after) < len(before):  # a later flight's row of one static station: read as sync reads it
            kept = pd.MultiIndex.from_frame(after[["t", "node"]].astype({"node": str}))
            poses[k] = poses[k][pd.MultiIndex.from_frame(poses[k][["t", "node"]].astype({"node": str})).isin(kept)]
    return poses, signals


__all__ = ["across_files", "drop_repeated_across", "file_damage", "fix_noise_m", "one_station", "refuse_overlaps",
           "signal_row_problems"]
