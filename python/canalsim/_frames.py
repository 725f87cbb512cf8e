"""Recordings between pandas and the compiled module: a DataFrame's columns are the recording's
columns in canalsim's units (docs/recording-format.md), its ``attrs`` the recording's metadata
("# key: value" lines); ``regime`` holds the words ``free`` and ``submerged``."""

from __future__ import annotations

import os
from typing import Union

import numpy as np
import pandas as pd

Recording = Union[str, os.PathLike, pd.DataFrame]

_REGIME_WORDS = ["free", "submerged"]  # by RegimeCode (core/recording.hpp)
_REGIME_DTYPE = pd.CategoricalDtype(_REGIME_WORDS)  # made once: pandas checks the categories each time
_REGIME_CODES = {"free": 0.0, "submerged": 1.0}


def frame(recording: dict) -> pd.DataFrame:
    """The compiled module's recording dict as a DataFrame."""
    columns = {}
    for name, values in zip(recording["names"], recording["columns"]):
        if name == "regime":
            columns[name] = pd.Categorical.from_codes(np.rint(values).astype(np.int8), dtype=_REGIME_DTYPE)
        else:
            columns[name] = values  # a float64 numpy array from the module
    df = pd.DataFrame(columns, copy=False)
    df.attrs = dict(recording["metadata"])
    df.attrs["source"] = recording["source"]
    return df


def recording(data: Recording, label: str) -> dict:
    """A recording dict for the compiled module from a path or a DataFrame; `label` names a
    DataFrame in messages ("recording 2")."""
    if isinstance(data, (str, os.PathLike)):
        from . import _canalsim
        return _canalsim.read_recording(os.fspath(data), {})
    if not isinstance(data, pd.DataFrame):
        raise TypeError(f"{label}: expected a path or a pandas.DataFrame, got {type(data).__name__}")
    names, columns = [], []
    for name in data.columns:
        values = data[name]
        if name == "regime" and not pd.api.types.is_numeric_dtype(values):
            unknown = set(values.dropna().unique()) - set(_REGIME_CODES)
            if unknown:
                from . import InputError
                raise InputError(f"{label}: column regime holds {sorted(unknown)[0]!r}, expected free or submerged")
            values = values.astype(object).map(_REGIME_CODES)
        names.append(str(name))
        columns.append(np.asarray(values, dtype=float))
    metadata = [(str(k), str(v)) for k, v in data.attrs.items() if k != "source"]
    source = str(data.attrs.get("source", label))
    return {"names": names, "columns": columns, "metadata": metadata, "source": source}


def recordings(data, label: str = "recording") -> list:
    """Recording dicts from one path/DataFrame or a list of them."""
    if isinstance(data, (str, os.PathLike, pd.DataFrame)):
        data = [data]
    return [recording(d, f"{label} {i + 1}") for i, d in enumerate(data)]
