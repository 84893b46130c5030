"""rplearn.io.tables: a signal table's ``unit`` column with an empty cell is refused on reading,
naming the file, the column and the file row (also in a later chunk)."""

from __future__ import annotations

import pandas as pd
import pytest

from rplearn.errors import InputError
from rplearn.io.tables import iter_signal_table, read_signal_table


def test_an_empty_unit_cell_names_file_column_and_file_row(tmp_path):
    n = 7
    sig = pd.DataFrame({"t": [0.1 * i for i in range(n)], "tx": "A", "rx": "B", "rssi_dbm": -60.0,
                        "tx_power_dbm": 20.0, "frequency_hz": 2.4e9, "unit": ["u1"] * 5 + [None, "u1"]})
    path = tmp_path / "sig.csv"
    sig.to_csv(path, index=False)
    with pytest.raises(InputError, match=rf"^{path}: column unit is empty at row 5 \(1 row\(s\)\)"):
        read_signal_table(str(path))
    with pytest.raises(InputError, match=rf"^{path}: column unit is empty at row 5 "):
        list(iter_signal_table(str(path), chunk_rows=3))
    sig.assign(unit="u1").to_csv(path, index=False)
    assert len(read_signal_table(str(path))[0]) == n
