"""Daylighting from Python (docs/daylighting.md): irradiance on planes, the calibration of a clear
sky, EPW files, and annual runs, serial, sharded and on a Dask LocalCluster of two workers, one of
which is killed while it works."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import atmo

SOURCE = os.environ.get("ATMO_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
GREENSBORO = os.path.join(SOURCE, "tests", "data", "greensboro_tmy3.epw")


def epw_excerpt(path, first_row, count):
    """The TMY3 file's 8 header lines and `count` rows from `first_row`."""
    with open(GREENSBORO, encoding="ascii") as f:
        lines = f.read().splitlines(keepends=True)
    with open(path, "w", encoding="ascii") as f:
        f.writelines(lines[:8] + lines[8 + first_row:8 + first_row + count])
    return path


def test_irradiance_of_the_horizontal_is_the_illuminance(earth):
    r = atmo.irradiance(35.0, 180.0, planes=[(0.0, 180.0), (90.0, 90.0), (90.0, 270.0), "sun"], model="hillaire",
                        preset="earth")
    e = earth.illuminance(35.0, night_sky=False)
    horizontal = r["planes"][0]
    sky = horizontal["circumsolar_lux"] + horizontal["sky_diffuse_lux"]
    assert sky == pytest.approx(e["diffuse_horizontal_lux"], rel=2e-3)
    assert horizontal["direct_lux"] == pytest.approx(e["direct_horizontal_lux"], rel=1e-9)
    # East and west walls under a sun in the south receive the same light.
    assert r["planes"][1]["global_lux"] == pytest.approx(r["planes"][2]["global_lux"], rel=1e-5)
    # The spectral components integrate to the broadband ones' order (3 channels: coarse), and the
    # plane facing the sun gets the direct normal.
    assert r["planes"][3]["direct_lux"] == pytest.approx(r["direct_normal_lux"], rel=1e-12)
    assert horizontal["global_spectral"].shape == (3,)
    with pytest.raises(ValueError, match="plane"):
        atmo.irradiance(35.0, planes=["up"], model="hillaire")


def test_calibration_round_trip():
    truth = atmo.calibrate(60000.0, 15000.0, 30.0, model="hillaire", preset="earth")
    assert truth["status"] == "clear"
    assert truth["direct_normal_lux"] == pytest.approx(60000.0, rel=0.005)
    assert truth["diffuse_horizontal_lux"] == pytest.approx(15000.0, rel=0.005)
    assert 0.0 < truth["aod_550"] < 2.0 and 0.5 <= truth["omega_550"] <= 1.0
    # Its parameters build a model that gives the same diffuse light.
    import json
    again = atmo.irradiance(30.0, planes=[(0.0, 180.0)], model="hillaire", config=json.loads(truth["parameters_json"]))
    assert again["planes"][0]["sky_diffuse_lux"] == pytest.approx(15000.0, rel=0.01)
    cloudy = atmo.calibrate(20000.0, 60000.0, 30.0, model="hillaire", preset="earth")
    assert cloudy["status"] == "too-much-diffuse" and "clouds" in cloudy["message"]


def test_read_epw():
    epw = atmo.read_epw(GREENSBORO)
    assert epw["location"]["wmo"] == "723170"
    hours = epw["hours"]
    assert hours["month"].shape == (8760,)
    assert np.nanmax(hours["direct_normal_lux"]) > 80000.0
    with pytest.raises(ValueError, match="cannot read"):
        atmo.read_epw("/nonexistent.epw")


def test_annual_shards_match_the_serial_run(tmp_path):
    epw = epw_excerpt(tmp_path / "two_days.epw", 4320, 48)
    kwargs = dict(model="hillaire", planes=[(30.0, 180.0)], per_wavelength=True)
    serial = atmo.annual(epw, tmp_path / "serial", **kwargs)
    assert serial["merged"] and serial["computed"] == 48
    first = atmo.annual(epw, tmp_path / "sharded", shard=(1, 2), **kwargs)
    assert not first["merged"]
    assert atmo.annual(epw, tmp_path / "sharded", shard=(0, 2), **kwargs)["merged"]
    # Each row of irradiance.csv (an hour with light and a plane) once per channel of the preset.
    spectral = (tmp_path / "serial" / "irradiance_spectral.csv").read_text().splitlines()
    broadband = (tmp_path / "serial" / "irradiance.csv").read_text().splitlines()
    assert spectral[0].startswith("hour,month,day,hour_of_day,plane,wavelength_nm,direct_w_m2_nm")
    assert len(broadband) > 1 + 3 * 20  # the two days' hours with light, 3 planes each
    assert len(spectral) - 1 == (len(broadband) - 1) * len(atmo.preset("us-standard")["wavelengths_nm"])
    for name in ("sky.mtx", "hours.csv", "irradiance.csv", "irradiance_spectral.csv"):
        assert (tmp_path / "sharded" / name).read_bytes() == (tmp_path / "serial" / name).read_bytes()


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # tornado, inside Debian's distributed 2022.12
def test_annual_on_dask_survives_a_killed_worker(tmp_path):
    distributed = pytest.importorskip("distributed")
    epw = epw_excerpt(tmp_path / "week.epw", 4320, 24 * 6)
    kwargs = dict(model="hillaire", planes=[(30.0, 180.0)])
    atmo.annual(epw, tmp_path / "serial", **kwargs)
    out = tmp_path / "dask"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=50) as cluster, distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        killed = {}

        def kill_a_working_worker():
            # As soon as a part is written, kill the worker computing that part's shard.
            deadline = time.time() + 120
            while time.time() < deadline and not killed:
                parts = list((out / "parts").glob("part-*.txt")) if (out / "parts").exists() else []
                for part in parts:
                    first_hour = int(part.name.split("-")[1])
                    key = f"atmo-annual-{(first_hour // 24) % 3}-of-3"
                    for address, keys in client.processing().items():
                        if key in keys and address in pids:
                            os.kill(pids[address], signal.SIGKILL)
                            killed[key] = address
                            return
                time.sleep(0.02)

        killer = threading.Thread(target=kill_a_working_worker)
        killer.start()
        seen = []
        result = atmo.annual_on_dask(client, epw, out, shards=3, progress=lambda done, total: seen.append((done, total)),
                                     **kwargs)
        killer.join()
    assert killed, "no worker was killed while computing (the shards ended too fast?)"
    assert result["merged"]
    assert seen[-1] == (3, 3) and [d for d, _ in seen] == [1, 2, 3]
    # The killed worker's shard was redone from its parts: it found hours already done.
    killed_shard = int(next(iter(killed)).split("-")[2])
    assert result["shards"][killed_shard]["already_done"] > 0
    for name in ("sky.mtx", "hours.csv", "irradiance.csv"):
        assert (out / name).read_bytes() == (tmp_path / "serial" / name).read_bytes()
