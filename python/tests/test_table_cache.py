"""The table cache from Python: off by default, a folder keeps source4d's tables, and a model
made again reads them back (the same radiance, bit for bit)."""

import os

import numpy as np
import pytest

import atmo

SMALL = {"table": "8x12x16x4", "gather": "17x5", "orders": "2"}


@pytest.fixture
def cache(tmp_path):
    atmo.set_table_cache(tmp_path / "tables")
    yield tmp_path / "tables"
    atmo.set_table_cache(None)


def files(folder):
    return sorted(name for name in os.listdir(folder) if name.endswith(".atmotables"))


def test_off_by_default():
    assert atmo.table_cache() is None


def test_a_second_model_reads_the_first_ones_tables(cache):
    first = atmo.Model("source4d", preset="earth", options=SMALL)
    assert atmo.table_cache() == str(cache)
    assert len(files(cache)) == 1
    second = atmo.Model("source4d", preset="earth", options=SMALL)
    assert len(files(cache)) == 1
    a = first.sample(0.0, [60.0, 93.0], [0.0, 85.0], 120.0).radiance
    b = second.sample(0.0, [60.0, 93.0], [0.0, 85.0], 120.0).radiance
    assert np.all(a > 0)
    np.testing.assert_array_equal(a, b)
    # Another atmosphere is another file.
    atmo.Model("source4d", preset="earth-spectral", options=SMALL)
    assert len(files(cache)) == 2


def test_bad_settings_are_refused():
    with pytest.raises(ValueError):
        atmo.set_table_cache("/tmp/x", max_bytes=0)
    with pytest.raises(ValueError):
        atmo.set_table_cache("/tmp/x", max_bytes=True)
    assert atmo.table_cache() is None
