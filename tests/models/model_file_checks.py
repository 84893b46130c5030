"""What the model-file tests share: the samples of a stored dataset of poses, the check that a
model predicts what ``rplearn predict`` wrote with it then, and the check that a binary sidecar
altered or missing is refused by name.

Imported by the test modules of this folder (pytest puts the folder on ``sys.path``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rplearn.data.tables import LinkSamples, link_samples, validate_matched
from rplearn.errors import ModelFileError
from rplearn.io.files import read_table
from rplearn.io.modelfile import named_sidecar
from rplearn.models.base import Model
from rplearn.models.load import load_model


def stored_samples(folder: Path) -> LinkSamples:
    """The link samples of ``folder/poses.csv``, a matched dataset without RSSI."""
    path = str(folder / "poses.csv")
    df = validate_matched(read_table(path), path, require_rssi=False)
    return link_samples(df, path, require_rssi=False)


def assert_predicts_as_stored(model: Model, samples: LinkSamples, predictions: Path) -> None:
    """Assert that ``model`` predicts ``samples``' gains (and spreads, where the CSV has them;
    none where it has not) as the CSV ``predictions`` holds them, within 1e-9 dB."""
    expected = pd.read_csv(predictions)
    assert len(expected) == len(samples), f"{predictions}: {len(expected)} rows for {len(samples)} samples"
    np.testing.assert_allclose(model.predict_gain(samples), expected["gain_pred_db"], rtol=0, atol=1e-9)
    std = model.predict_gain_std(samples)
    if "gain_pred_std_db" in expected.columns:
        np.testing.assert_allclose(std, expected["gain_pred_std_db"], rtol=0, atol=1e-9)
    else:
        assert std is None, f"{predictions} holds no spreads, the model predicts some"


def assert_sidecar_refused_altered_then_missing(path: Path, flip: int) -> None:
    """Alter a byte of the sidecar of the model file ``path`` (XOR ``flip``) and assert that
    loading it is refused as a checksum mismatch; then remove the sidecar and assert that it is
    refused as missing."""
    side = named_sidecar(path)
    data = bytearray(open(side, "rb").read())
    data[-100] ^= flip
    open(side, "wb").write(bytes(data))
    with pytest.raises(ModelFileError, match="checksum mismatch"):
        load_model(path)
    os.remove(side)
    with pytest.raises(ModelFileError, match="sidecar is missing"):
        load_model(path)
