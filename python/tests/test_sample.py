"""Model.sample: agreement with `atmo sample`, NumPy broadcasting, and the physics of its values."""

import numpy as np
import pytest

import atmo
from conftest import assert_printed, parse_csv

# Rows of a grid: observers on the ground, on a mountain, in orbit and below the horizon's sun.
GRID = [
    (0.0, 30.0, 0.0, 0.0),
    (0.0, 60.0, 80.0, 90.0),
    (1000.0, 85.0, 89.0, 180.0),
    (0.0, 45.0, 120.0, 30.0),     # looking at the ground
    (8848.0, 96.0, 70.0, 10.0),   # sun below the horizon
    (400e3, 40.0, 100.0, 250.0),  # from orbit, towards the limb
    (0.0, 30.0, 45.0, -45.0),
]


def grid_text(rows):
    return "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg\n" + "".join(
        f"{a!r},{s!r},{v!r},{z!r}\n" for a, s, v, z in rows)


def module_arrays(rows):
    return [np.array([row[k] for row in rows]) for k in range(4)]


@pytest.mark.parametrize("unit", ["relative", "radiance"])
def test_matches_atmo_sample_per_channel(earth, cli, unit):
    printed = parse_csv(cli("sample", "--model", "hillaire", "--preset", "earth", "--grid", "-", "--unit", unit, stdin=grid_text(GRID)))
    r = earth.sample(*module_arrays(GRID), unit=unit)
    nc = earth.channel_count
    assert len(printed) == len(GRID) * nc
    for i in range(len(GRID)):
        for c in range(nc):
            row = printed[i * nc + c]
            assert row["wavelength_nm"] == pytest.approx(earth.wavelengths_nm[c])
            assert_printed(r.radiance[i, c], row["radiance"])
            assert_printed(r.transmittance[i, c], row["transmittance"])
            assert_printed(r.standard_error[i, c], row["stderr"])


def test_matches_atmo_sample_in_luminance_and_spectral(cli):
    model = atmo.Model("hillaire", preset="earth", spectral=8)
    printed = parse_csv(cli("sample", "--model", "hillaire", "--preset", "earth", "--spectral", "8", "--unit", "luminance", "--grid", "-",
                            stdin=grid_text(GRID)))
    r = model.sample(*module_arrays(GRID), unit="luminance")
    assert r.radiance.shape == (len(GRID), 1)
    for i, row in enumerate(printed):
        assert_printed(r.radiance[i, 0], row["luminance_cd_m2"])
        assert_printed(r.transmittance[i, 0], row["luminous_transmittance"])


@pytest.mark.parametrize("model_name,extra", [("elek", ["--preset", "atmosphere-plus"]),
                                              ("simple", ["--preset", "simple"])])
def test_matches_atmo_sample_for_other_models(cli, model_name, extra):
    rows = [(0.0, 30.0, 10.0, 0.0), (500.0, 70.0, 85.0, 120.0), (0.0, 50.0, 60.0, 200.0)]
    printed = parse_csv(cli("sample", "--model", model_name, *extra, "--grid", "-", stdin=grid_text(rows)))
    model = atmo.Model(model_name, preset=extra[1])
    r = model.sample(*module_arrays(rows))
    nc = model.channel_count
    for i in range(len(rows)):
        for c in range(nc):
            assert_printed(r.radiance[i, c], printed[i * nc + c]["radiance"])
            assert_printed(r.transmittance[i, c], printed[i * nc + c]["transmittance"])


def test_matches_atmo_sample_with_options(cli):
    rows = [(0.0, 30.0, 0.0, 0.0), (0.0, 80.0, 85.0, 30.0)]
    printed = parse_csv(cli("sample", "--model", "hillaire", "--preset", "earth", "--option", "multiple_scattering_directions=2", "--grid", "-",
                            stdin=grid_text(rows)))
    model = atmo.Model("hillaire", preset="earth", options={"multiple_scattering_directions": 2})
    r = model.sample(*module_arrays(rows))
    for i in range(len(rows)):
        for c in range(3):
            assert_printed(r.radiance[i, c], printed[3 * i + c]["radiance"])


def test_monte_carlo_reference_matches_atmo_sample_with_its_seed(cli):
    # The reference model's estimate depends only on its seed, the query and the path count, so
    # the module's parallel evaluation gives the CLI's numbers, standard errors included.
    rows = [(0.0, 40.0, 60.0, 90.0), (0.0, 70.0, 30.0, 180.0)]
    printed = parse_csv(cli("sample", "--preset", "earth", "--model", "reference", "--samples", "64", "--seed", "3", "--grid", "-",
                            stdin=grid_text(rows)))
    model = atmo.Model("reference", preset="earth", options={"samples": 64}, seed=3)
    r = model.sample(*module_arrays(rows))
    assert np.all(r.standard_error > 0.0)
    for i in range(len(rows)):
        for c in range(3):
            assert_printed(r.radiance[i, c], printed[3 * i + c]["radiance"])
            assert_printed(r.standard_error[i, c], printed[3 * i + c]["stderr"])


def test_broadcasting_gives_the_pointwise_values(earth):
    altitude = np.array([0.0, 2000.0])[:, None, None]             # (2, 1, 1)
    view_zenith = np.linspace(0.0, 170.0, 5)[None, :, None]        # (1, 5, 1)
    azimuth = np.array([0.0, 45.0, 180.0])[None, None, :]          # (1, 1, 3)
    r = earth.sample(altitude, 60.0, view_zenith, azimuth)
    assert r.radiance.shape == (2, 5, 3, 3)
    assert r.transmittance.shape == (2, 5, 3, 3)
    for i, a in enumerate(altitude.ravel()):
        for j, v in enumerate(view_zenith.ravel()):
            for k, z in enumerate(azimuth.ravel()):
                one = earth.sample(a, 60.0, v, z)
                assert one.radiance.shape == (3,)
                np.testing.assert_array_equal(r.radiance[i, j, k], one.radiance)
                np.testing.assert_array_equal(r.transmittance[i, j, k], one.transmittance)


def test_float32_results_are_the_rounded_float64_ones(earth):
    v = np.linspace(0.0, 90.0, 7)
    r64 = earth.sample(0.0, 50.0, v, 30.0)
    r32 = earth.sample(0.0, 50.0, v, 30.0, dtype=np.float32)
    assert r32.radiance.dtype == np.float32
    np.testing.assert_array_equal(r32.radiance, r64.radiance.astype(np.float32))


def test_sky_is_symmetric_about_the_suns_vertical_plane(earth):
    # A horizontally uniform atmosphere: the sky at azimuth +phi from the sun equals that at -phi
    # and at 360 - phi.
    phi = np.linspace(0.0, 180.0, 13)
    view_zenith = np.array([10.0, 60.0, 89.0, 100.0])[:, None]
    for sun_zenith in (20.0, 75.0, 93.0):
        plus = earth.sample(0.0, sun_zenith, view_zenith, phi)
        minus = earth.sample(0.0, sun_zenith, view_zenith, -phi)
        wrapped = earth.sample(0.0, sun_zenith, view_zenith, 360.0 - phi)
        np.testing.assert_allclose(minus.radiance, plus.radiance, rtol=1e-12)
        np.testing.assert_allclose(wrapped.radiance, plus.radiance, rtol=1e-9)
        # The transmittance does not depend on the azimuth at all.
        np.testing.assert_array_equal(plus.transmittance, np.broadcast_to(plus.transmittance[:, :1], plus.transmittance.shape))


def test_sky_is_brighter_towards_the_sun(earth):
    # Forward scattering (Mie) and the Rayleigh phase peak: at view zenith = sun zenith the sky
    # near the sun outshines the sky opposite it, in every channel.
    r = earth.sample(0.0, 60.0, 60.0, np.array([10.0, 90.0]))
    assert np.all(r.radiance[0] > r.radiance[1])


def test_transmittance_is_in_unit_interval_and_falls_towards_the_horizon(earth):
    view_zenith = np.linspace(0.0, 89.9, 200)
    r = earth.sample(0.0, 30.0, view_zenith, 0.0)
    t = r.transmittance
    assert np.all((t >= 0.0) & (t <= 1.0))
    assert np.all(np.diff(t, axis=0) <= 0.0)
    # Rayleigh extinction grows towards the blue: the blue channel is attenuated most.
    assert np.all(t[:, 2] < t[:, 0])
    assert np.all(r.radiance >= 0.0)


def test_transmittance_is_one_looking_up_above_the_atmosphere_and_zero_into_the_ground(earth):
    above = earth.top_altitude_m + 1000.0
    up = earth.sample(above, 30.0, np.linspace(0.0, 80.0, 9), 0.0)
    np.testing.assert_array_equal(up.transmittance, 1.0)
    np.testing.assert_array_equal(up.radiance, 0.0)  # nothing scatters above the atmosphere
    down = earth.sample(0.0, 30.0, np.linspace(95.0, 180.0, 9), 0.0)
    np.testing.assert_array_equal(down.transmittance, 0.0)


def test_vertical_transmittance_matches_the_optical_depth_of_the_column(earth):
    # Straight up from the ground, T = exp(-tau) with tau the column's optical depth: Rayleigh
    # (8 km scale height) + Mie (1.2 km) + the ozone tent, from the preset's coefficients. The
    # gap is the transmittance table's interpolation and quadrature, a few 1e-4.
    p = earth.parameters()
    t = earth.sample(0.0, 30.0, 0.0, 0.0).transmittance

    def column(medium, h_max=earth.top_altitude_m, steps=20000):
        h = np.linspace(0.0, h_max, steps + 1)
        layers = medium["density"]
        density = np.empty_like(h)
        for i, x in enumerate(h):
            layer = layers["lower"] if x < layers["lower"]["width_m"] else layers["upper"]
            d = (layer["exp_term"] * np.exp(layer["exp_scale_per_m"] * x) + layer["linear_term_per_m"] * x
                 + layer["constant_term"])
            density[i] = min(max(d, 0.0), 1.0)
        integral = np.trapz(density, h)
        return (np.asarray(medium["scattering_per_m"]) + np.asarray(medium["absorption_per_m"])) * integral

    tau = column(p["rayleigh"]) + column(p["mie"]) + column(p["ozone"])
    np.testing.assert_allclose(t, np.exp(-tau), rtol=2e-3)


def test_spectral_model_has_its_channels(cli):
    model = atmo.Model("hillaire", preset="earth", spectral=16)
    assert model.channel_count == 16
    w = model.wavelengths_nm
    assert w.shape == (16,) and np.all(np.diff(w) > 0) and w[0] >= 360.0 and w[-1] <= 830.0
    assert len(model.channel_names) == 16 and model.channel_names[0].endswith("nm")
    r = model.sample(0.0, 40.0, [0.0, 60.0], 90.0)
    assert r.radiance.shape == (2, 16)
    assert r.wavelengths_nm == tuple(w)
    # Rayleigh: the clear zenith sky is bluer than red per unit solar irradiance.
    assert r.radiance[0, 0] > r.radiance[0, -1]
    # unit radiance multiplies each channel by the solar spectral irradiance at its wavelength.
    rr = model.sample(0.0, 40.0, [0.0, 60.0], 90.0, unit="radiance")
    np.testing.assert_allclose(rr.radiance, r.radiance * model.solar_spectral_irradiance, rtol=1e-12)


def test_config_dict_path_and_preset_agree(tmp_path, earth):
    parameters = atmo.preset("earth")
    path = tmp_path / "earth.json"
    path.write_text(__import__("json").dumps(parameters))
    v = np.array([0.0, 70.0, 89.0])
    reference = earth.sample(0.0, 60.0, v, 45.0).radiance
    np.testing.assert_array_equal(atmo.Model("hillaire", config=parameters).sample(0.0, 60.0, v, 45.0).radiance,
                                  reference)
    np.testing.assert_array_equal(atmo.Model("hillaire", config=str(path)).sample(0.0, 60.0, v, 45.0).radiance,
                                  reference)
    # A hazier atmosphere (ten times the aerosol) transmits less.
    parameters["mie"]["scattering_per_m"] = [10 * x for x in parameters["mie"]["scattering_per_m"]]
    hazy = atmo.Model("hillaire", config=parameters)
    assert np.all(hazy.sample(0.0, 60.0, v, 45.0).transmittance < earth.sample(0.0, 60.0, v, 45.0).transmittance)


def test_concurrent_queries_from_python_threads_agree(earth):
    # sample releases the GIL and shares the model's cached views between threads: queries from
    # several Python threads at once give what each gives alone.
    import threading

    rng = np.random.default_rng(4)
    jobs = [(float(a), float(s), rng.uniform(0, 180, 2000), rng.uniform(-180, 180, 2000))
            for a, s in [(0.0, 30.0), (500.0, 80.0), (0.0, 30.0), (12e3, 91.0), (0.0, 60.0), (500.0, 80.0)]]
    alone = [earth.sample(*job).radiance for job in jobs]
    together = [None] * len(jobs)

    def run(k):
        together[k] = earth.sample(*jobs[k]).radiance

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a, b)


def test_radiance_batch_is_the_float_path_of_sample(earth):
    # The renderer's float sky-view kernel against sample's double lookup of the same table:
    # equal to float rounding and the kernel's float interpolation weights (1e-4 relative).
    rng = np.random.default_rng(5)
    view_zenith = rng.uniform(0.0, 89.0, 500)
    azimuth = rng.uniform(-180.0, 180.0, 500)
    z, a = np.radians(view_zenith), np.radians(azimuth)
    directions = np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], axis=-1)
    batch = earth.radiance_batch(0.0, 50.0, directions.reshape(25, 20, 3))
    assert batch.dtype == np.float32 and batch.shape == (25, 20, 3)
    sampled = earth.sample(0.0, 50.0, view_zenith, azimuth).radiance
    np.testing.assert_allclose(batch.reshape(500, 3), sampled, rtol=1e-4)
    # The sun disc adds its radiance only along directions inside the disc.
    sun = atmo.sun_direction(40.0, 0.0)
    with_disc = earth.radiance_batch(0.0, 50.0, np.stack([sun, directions[0]]), sun_disc=True)
    without = earth.radiance_batch(0.0, 50.0, np.stack([sun, directions[0]]))
    assert np.all(with_disc[0] > 100 * without[0]) and np.array_equal(with_disc[1], without[1])


def test_results_do_not_depend_on_the_thread_count(earth):
    rng = np.random.default_rng(6)
    args = (rng.choice([0.0, 900.0], 3000), rng.choice([20.0, 70.0], 3000), rng.uniform(0, 180, 3000),
            rng.uniform(-180, 180, 3000))
    everywhere = earth.sample(*args).radiance
    atmo.set_threads(1)
    try:
        one = earth.sample(*args).radiance
    finally:
        atmo.set_threads(0)
    np.testing.assert_array_equal(one, everywhere)
    with pytest.raises(ValueError, match="threads"):
        atmo.set_threads(-1)


def test_a_huge_broadcast_is_refused_before_it_is_copied(earth):
    # 50000 x 50000 points: 2.5e9, which the copies of the broadcast inputs alone would need 80 GB
    # for (a 20 GB address-space allocation before this bound).
    a = np.zeros(50000)
    with pytest.raises(ValueError) as error:
        earth.sample(a, 30.0, a[:, None], 0.0)
    assert "2500000000 points" in str(error.value) and "GiB" in str(error.value)
    assert "\n" not in str(error.value)
