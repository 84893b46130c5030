"""Named radios and their datasheet sensitivity, for ``--sensitivity`` (docs/availability.md cites
each source).

A radio's *sensitivity* is the weakest received power at which it still decodes its frames
(at a stated error rate and data rate). :func:`sensitivity_dbm` turns a number of dBm, or the
name of a preset in :data:`RADIO_PRESETS`, into that level.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import BadValueError, InputError


@check_types
@dataclass(frozen=True)
class RadioPreset:
    """A common radio at one data rate and its datasheet sensitivity.

    Attributes
    ----------
    name : str
        What ``--sensitivity`` accepts.
    sensitivity_dbm : float
        The weakest received power the radio decodes at that rate [dBm].
    band : str
        Its band(s), for people.
    mode : str
        The data rate or mode the sensitivity is stated for.
    source : str
        Where the figure comes from (the docs give the citation).
    """

    name: str
    sensitivity_dbm: float
    band: str
    mode: str
    source: str


#: The named radios ``--sensitivity`` knows (docs/availability.md lists their citations).
RADIO_PRESETS: dict[str, RadioPreset] = {p.name: p for p in (
    RadioPreset("sik", -121.0, "433/915 MHz", "SiK firmware (HopeRF HM-TRP, RFD900), lowest air data rate",
                "ArduPilot SiK telemetry radio documentation; Silicon Labs Si4430/31/32 datasheet"),
    RadioPreset("rfd900", -121.0, "900 MHz", "RFD900 family, lowest air data rate",
                "ArduPilot SiK telemetry radio documentation (RFD900 hardware); Silicon Labs Si4430/31/32 datasheet"),
    RadioPreset("esp32-11b", -97.0, "2.4 GHz", "ESP32 Wi-Fi, 802.11b 1 Mbit/s",
                "Espressif ESP32 series datasheet, Wi-Fi receiver characteristics"),
    RadioPreset("wifi-6mbps", -82.0, "2.4/5 GHz", "IEEE 802.11 OFDM, 6 Mbit/s, 20 MHz (the standard's minimum)",
                "IEEE Std 802.11, OFDM PHY receiver minimum input sensitivity table"),
    RadioPreset("wifi-54mbps", -65.0, "2.4/5 GHz", "IEEE 802.11 OFDM, 54 Mbit/s, 20 MHz (the standard's minimum)",
                "IEEE Std 802.11, OFDM PHY receiver minimum input sensitivity table"),
    RadioPreset("rx5808", -90.0, "5.8 GHz", "analog FM video receiver module (RichWave RTC6715)",
                "RX5808 module specification as sold (vendor listing; no formal error-rate definition)"),
)}


@check_types
def sensitivity_dbm(value: str | float) -> float:
    """A sensitivity [dBm] from a number (``-95``, ``"-95"``) or a preset name (``"sik"``).

    Raises
    ------
    InputError
        (``param="sensitivity"``) for an unknown name, a non-finite number or one outside
        -200..0 dBm.
    """
    if isinstance(value, str):
        key = value.strip().lower()
        if key in RADIO_PRESETS:
            return RADIO_PRESETS[key].sensitivity_dbm
        try:
            number = float(key)
        except ValueError:
            raise BadValueError(f"sensitivity: {value!r} is neither a level in dBm nor a radio preset; presets: "
                             f"{', '.join(RADIO_PRESETS)}", param="sensitivity") from None
    else:
        number = float(value)
    if not (np.isfinite(number) and -200.0 <= number <= 0.0):
        raise InputError(f"sensitivity: expected a level in dBm between -200 and 0, got {value!r}", param="sensitivity")
    return number


__all__ = ["RADIO_PRESETS", "RadioPreset", "sensitivity_dbm"]
