"""The gases of the standard-atmosphere presets (O2, O2-O2, water vapour; docs/parameters.md,
"Gases") through Python: `wavelengths=` is the command line's --wavelengths, and a 10 nm channel on
the O2-A band sees the band's absorption."""
import numpy as np
import pytest

import atmo
from conftest import parse_csv


def test_wavelengths_match_atmo_sample_and_see_the_a_band(cli):
    model = atmo.Model("hillaire", preset="us-standard", wavelengths=[755, 765, 775])
    result = model.sample(altitude_m=0.0, sun_zenith_deg=48.236, view_zenith_deg=48.236, azimuth_deg=0.0)
    rows = parse_csv(cli("sample", "--model", "hillaire", "--preset", "us-standard", "--wavelengths", "755,765,775",
                         "--altitude", "0", "--sun-zenith", "48.236", "--view-zenith", "48.236", "--azimuth", "0"))
    expected = np.array([float(r["transmittance"]) for r in rows])
    t = np.asarray(result.transmittance).ravel()
    np.testing.assert_allclose(t, expected, rtol=1e-6)
    # Along the sun at air mass 1.5 the A band keeps 0.62 of the light of its neighbours
    # (ASTM G-173: 0.615); without the gases it would keep all of it.
    assert 0.55 < t[1] / np.sqrt(t[0] * t[2]) < 0.70


@pytest.mark.parametrize("keywords,message", [
    ({"wavelengths": [300.0, 400.0]}, "outside [360, 830] nm"),
    ({"wavelengths": [500.0, 400.0]}, "must increase"),
])
def test_bad_wavelengths_get_one_line_errors(keywords, message):
    with pytest.raises(ValueError) as error:
        atmo.Model("hillaire", preset="us-standard", **keywords)
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("keywords", [{"wavelengths": [], "spectral": 0}, {"wavelengths": [500.0], "spectral": 5},
                                      {"wavelengths": [[500.0]]}, {"wavelengths": ["a"]}])
def test_malformed_wavelengths_are_refused(keywords):
    with pytest.raises(ValueError):
        atmo.Model("hillaire", preset="us-standard", **keywords)


def test_max_memory_refuses_large_tables_before_allocating():
    default = atmo.max_memory()
    try:
        atmo.set_max_memory("256M")
        assert atmo.max_memory() == 256 * 1024 * 1024
        with pytest.raises(ValueError) as error:
            atmo.Model("source4d", preset="earth", options={"table": "64x64x64x64"})
        assert "would need about 1.0 GB, more than the memory limit of 256.0 MB" in str(error.value)
        with pytest.raises(ValueError):
            atmo.set_max_memory("4X")
    finally:
        atmo.set_max_memory(None)
    assert atmo.max_memory() == default
