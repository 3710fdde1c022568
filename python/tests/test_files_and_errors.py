"""EXR/PNG writing through atmo's atomic writers, and the errors bad input raises."""

import math
import struct

import numpy as np
import pytest

import atmo


def png_header(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height, bits, colour_type = struct.unpack(">IIBB", data[16:26])
    return width, height, bits, colour_type


def test_exr_round_trip_keeps_values_names_alpha_and_metadata(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 4), dtype=np.float32) * 1e4
    alpha = (rng.random((5, 7)) > 0.5).astype(np.float32)
    path = tmp_path / "x.exr"
    atmo.write_exr(path, image, alpha=alpha, channel_names=["C0", "C1", "C2", "C3"], metadata={"note": "hi"})
    read, read_alpha, names, metadata = atmo.read_exr(path)
    np.testing.assert_array_equal(read, image)
    np.testing.assert_array_equal(read_alpha, alpha)
    assert names == ("C0", "C1", "C2", "C3") and metadata["note"] == "hi"
    assert [p.name for p in tmp_path.iterdir()] == ["x.exr"]  # no temporary left behind


def test_frame_writes_exr_with_metadata_and_png(tmp_path, earth):
    frame = earth.render(32, 16, "equirect", sun_elevation_deg=20.0, full=True)
    frame.write_exr(tmp_path / "f.exr")
    frame.write_png(tmp_path / "f.png")
    image, _, names, metadata = atmo.read_exr(tmp_path / "f.exr")
    np.testing.assert_array_equal(image, frame.image)
    assert metadata["atmo:model"] == "hillaire" and metadata["atmo:camera"] == "equirect"
    assert metadata["atmo:sunElevationDeg"] == "20"
    assert png_header(tmp_path / "f.png") == (32, 16, 8, 2)  # 8-bit RGB


def test_png_exposure_and_bits(tmp_path, earth):
    image = earth.render(16, 16, "fisheye")
    alpha = earth.render(16, 16, "fisheye", full=True).alpha
    atmo.write_png(tmp_path / "a.png", image, alpha=alpha, bits=16, ev100=14.0)
    assert png_header(tmp_path / "a.png") == (16, 16, 16, 6)  # 16-bit RGBA
    # The camera meter maps the log-average luminance to 1 / 9.6 of the saturation luminance
    # (include/atmo/image.h): a brighter image gets a larger EV100, by log2 of the factor.
    ev = atmo.auto_exposure_ev100(image, alpha, metering="camera")
    assert atmo.auto_exposure_ev100(image * 4.0, alpha, metering="camera") == pytest.approx(ev + 2.0, abs=1e-4)
    # The adaptive meter (the default) gives the brighter image a higher key: less than 2 stops.
    adaptive = atmo.auto_exposure_ev100(image, alpha)
    assert 1.0 < atmo.auto_exposure_ev100(image * 4.0, alpha) - adaptive < 2.0
    with pytest.raises(ValueError, match="unknown metering"):
        atmo.auto_exposure_ev100(image, alpha, metering="spot")
    assert atmo.exposure_from_ev100(ev) == pytest.approx(1.0 / (1.2 * 2.0**ev))


def test_failed_write_leaves_the_old_file(tmp_path):
    path = tmp_path / "keep.exr"
    atmo.write_exr(path, np.ones((2, 2, 3), np.float32))
    before = path.read_bytes()
    with pytest.raises(ValueError, match="cannot write"):
        atmo.write_exr(path, np.ones((2, 2, 3), np.float32), channel_names=["R", "R", "B"])
    assert path.read_bytes() == before
    with pytest.raises(ValueError, match="does not exist"):
        atmo.write_png(tmp_path / "missing" / "x.png", np.ones((2, 2, 3), np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.exr"]


@pytest.mark.parametrize("make,message", [
    (lambda: atmo.Model("nosuch"), "nosuch"),
    (lambda: atmo.Model("hillaire", preset="mars"), "mars"),
    (lambda: atmo.Model("hillaire", options={"bogus": 1}), "bogus"),
    (lambda: atmo.Model("hillaire", options={"sky_view": "maybe"}), "sky_view"),
    (lambda: atmo.Model("hillaire", config={"rayleigh": {"scattering_per_m": [-1, 0, 0]}}), "scattering"),
    (lambda: atmo.Model("hillaire", config={"no_such_key": 1}), "no_such_key"),
    (lambda: atmo.Model("hillaire", config="/nonexistent/x.json"), "/nonexistent/x.json"),
    (lambda: atmo.Model("hillaire", preset="earth", config={}), "not both"),
    (lambda: atmo.Model("hillaire", spectral=2), "spectral"),
    (lambda: atmo.Model("reference", seed=-1), "seed"),
])
def test_bad_models_raise_value_error_with_one_line(make, message):
    with pytest.raises(ValueError, match=message) as error:
        make()
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("args,kwargs,message", [
    ((0.0, 190.0, 0.0, 0.0), {}, r"sun_zenith_deg 190 is outside \[0, 180\]"),
    ((0.0, 30.0, [0.0, 10.0, -5.0], 0.0), {}, r"sample \[2\]: view_zenith_deg -5"),
    (([[0.0, math.nan]], 30.0, 0.0, 0.0), {}, r"sample \[0, 1\]: altitude_m is not a finite number"),
    ((2e11, 30.0, 0.0, 0.0), {}, "altitude_m"),
    (([0.0, 1.0], 30.0, [0.0, 1.0, 2.0], 0.0), {}, "broadcast"),
    ((0.0, 30.0, 0.0, 0.0), {"unit": "lux"}, "unit"),
    ((0.0, 30.0, 0.0, 0.0), {"dtype": np.int32}, "dtype"),
])
def test_bad_samples_raise_value_error(earth, args, kwargs, message):
    with pytest.raises(ValueError, match=message):
        earth.sample(*args, **kwargs)


@pytest.mark.parametrize("kwargs,message", [
    (dict(width=0, height=10), "image size"),
    (dict(width=10, height=10, camera="pinhole"), "camera"),
    (dict(width=10, height=10, fov_deg=180.0), "fov"),
    (dict(width=10, height=10, sun_elevation_deg=math.inf), "finite"),
    (dict(width=10, height=10, unit="relative", xyz=True), "xyz"),
    (dict(width=10, height=10, spp=4), "deterministic"),
    (dict(width=4, height=5, camera="cubemap"), "cubemap"),
])
def test_bad_renders_raise_value_error(earth, kwargs, message):
    with pytest.raises(ValueError, match=message):
        earth.render(**kwargs)


def test_bad_images_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="3 channels"):
        atmo.write_png(tmp_path / "x.png", np.ones((2, 2, 4), np.float32))
    with pytest.raises(ValueError, match="alpha"):
        atmo.write_exr(tmp_path / "x.exr", np.ones((2, 2, 3), np.float32), alpha=np.ones((3, 2), np.float32))
    with pytest.raises(ValueError, match="tone"):
        atmo.write_png(tmp_path / "x.png", np.ones((2, 2, 3), np.float32), tonemap="filmic")
    with pytest.raises(ValueError, match="bits"):
        atmo.write_png(tmp_path / "x.png", np.ones((2, 2, 3), np.float32), bits=12)


@pytest.mark.parametrize("image,message", [
    (np.zeros((2, 3, 3), dtype=np.complex64), "an image must be real numbers (got complex64)"),
    (np.array([["a", "b"]]), "an image must be numbers"),
    (np.broadcast_to(np.float32(0), (4, 16385, 3)), "an image of 16385 x 4 pixels is too large"),
    (np.broadcast_to(np.float32(0), (6 * 16384 + 1, 4, 3)), "at most 16384 wide and 98304 high"),
])
def test_writers_refuse_complex_and_oversized_images_before_copying(tmp_path, image, message):
    # The audit's N7: complex input was cast with a warning, images wider than 16384 were written.
    for write in (atmo.write_exr, atmo.write_png):
        target = tmp_path / ("x.exr" if write is atmo.write_exr else "x.png")
        with pytest.raises(ValueError) as error:
            write(target, image)
        assert message in str(error.value)
        assert not target.exists()
