"""The aerosol keywords of atmo.Model: the command line's --aerosol, --aod, --angstrom,
--visibility and --turbidity (docs/aerosols.md), checked against `atmo sample` with the same
flags, and their one-line errors."""
import numpy as np
import pytest

import atmo
from conftest import parse_csv


def test_aerosol_types_are_listed():
    types = atmo.aerosol_types()
    assert "continental-average" in types and "urban" in types and len(types) == 10


@pytest.mark.parametrize("keywords,flags", [
    ({"aerosol": "urban", "aod": 0.4}, ["--aerosol", "urban", "--aod", "0.4"]),
    ({"visibility": 15.0}, ["--visibility", "15"]),
    ({"aerosol": "desert", "angstrom": 0.5}, ["--aerosol", "desert", "--angstrom", "0.5"]),
    ({"turbidity": 3.5}, ["--turbidity", "3.5"]),
    ({"aerosol": "maritime-clean", "aerosol_phase": "opac"}, ["--aerosol", "maritime-clean", "--aerosol-phase", "opac"]),
])
def test_keywords_match_atmo_sample_with_the_flags(cli, keywords, flags):
    model = atmo.Model("hillaire", preset="us-standard", spectral=5, **keywords)
    result = model.sample(altitude_m=0.0, sun_zenith_deg=50.0, view_zenith_deg=70.0, azimuth_deg=30.0)
    rows = parse_csv(cli(*["sample", "--model", "hillaire", "--preset", "us-standard", "--spectral", "5",
                          "--altitude", "0", "--sun-zenith", "50", "--view-zenith", "70", "--azimuth", "30"], *flags))
    expected = np.array([float(r["radiance"]) for r in rows])
    np.testing.assert_allclose(np.asarray(result.radiance).ravel(), expected, rtol=1e-6)
    # The knob changed the sky: the preset's own aerosol gives other values.
    plain = atmo.Model("hillaire", preset="us-standard", spectral=5).sample(
        altitude_m=0.0, sun_zenith_deg=50.0, view_zenith_deg=70.0, azimuth_deg=30.0)
    assert np.max(np.abs(np.asarray(plain.radiance).ravel() / expected - 1)) > 0.01


@pytest.mark.parametrize("keywords,message", [
    ({"aerosol": "smog"}, "unknown aerosol type 'smog'"),
    ({"aod": 11.0}, "outside [0, 10]"),
    ({"angstrom": 5.0}, "outside [-1, 4]"),
    ({"visibility": -1.0}, "must be positive"),
    ({"aod": 0.1, "visibility": 20.0}, "at most one of"),
    ({"aod": "0.1"}, "aod must be a number"),
])
def test_bad_keywords_raise_one_line_errors(keywords, message):
    with pytest.raises(ValueError, match=None) as error:
        atmo.Model("hillaire", preset="us-standard", **keywords)
    assert message in str(error.value)
    assert "\n" not in str(error.value)
