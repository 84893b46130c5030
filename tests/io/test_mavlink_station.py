"""The GPS accuracy a ``.tlog`` reports for the fix that placed its station (rplearn.io._mavlink_station)."""

from __future__ import annotations

from rplearn.io._mavlink_records import TlogRows, tlog_raw
from rplearn.io._mavlink_station import accuracy_at


def test_the_station_accuracy_is_a_3d_fixs_not_the_receivers_before_its_fix():
    # GPS_RAW_INT every 0.2 s: 2 s without a fix (h_acc/v_acc 45/80 m), then a 3-D fix (1.2/2.0 m); the vehicle's
    # position is valid from the fix's tick, its message logged just before that tick's GPS_RAW_INT. The station
    # placed at that first position has the fix's accuracy (was: the last no-fix message's, 45/80 m)
    acc = TlogRows()
    sender = 1 * 256 + 1
    for k in ("HOME_POSITION", "GPS_GLOBAL_ORIGIN", "HEARTBEAT", "RADIO_STATUS", "RADIO"):
        acc.rows[k] = []
    acc.rows["ATTITUDE"], acc.rows["GPS_RAW_INT"], acc.rows["GLOBAL_POSITION_INT"] = [], [], []
    for i in range(20):
        t, fix = 100.0 + 0.2 * i, i >= 10
        acc.rows["ATTITUDE"].append((sender, t, t - 50.0, 0.0, 0.0, 0.0))
        acc.rows["GPS_RAW_INT"].append((sender, t + 0.001, float(fix), 1.2 if fix else 45.0, 2.0 if fix else 80.0))
        if fix:
            acc.rows["GLOBAL_POSITION_INT"].append((sender, t, t - 50.0, 47.39, 8.54, 500.0, 0.0, 0.0))
    acc.counts = {k: len(v) for k, v in acc.rows.items()}
    raw = tlog_raw(acc, "demo.tlog", None, {})
    assert accuracy_at(raw.accuracy, float(raw.pos[0, 0])) == (1.2, 2.0)
