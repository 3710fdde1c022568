"""Model.render: shapes per camera, agreement with RadianceBatch and with sample, `atmo render`."""

import numpy as np
import pytest

import atmo


@pytest.mark.parametrize("camera,size,shape", [
    ("perspective", (64, 36), (36, 64, 3)),
    ("fisheye", (48, 48), (48, 48, 3)),
    ("equirect", (64, 32), (32, 64, 3)),
    ("cubemap", (16, None), (96, 16, 3)),
])
def test_every_camera_gives_a_float32_image(earth, camera, size, shape):
    image = earth.render(*size, camera=camera, sun_elevation_deg=20.0)
    assert image.dtype == np.float32 and image.shape == shape
    assert np.all(np.isfinite(image)) and np.all(image >= 0.0)
    assert image.max() > 0.0


def test_relative_frame_equals_radiance_batch_of_its_pixel_directions(earth):
    # The frame pass is RadianceBatch on the camera's pixel directions times the preset's solar
    # irradiance (the sun disc and the night sky have their own passes: left out here). The sun lies
    # at compass azimuth 0, the convention of radiance_batch and sample.
    for camera, (w, h), kwargs in [("perspective", (40, 24), dict(fov_deg=70.0, yaw_deg=30.0, pitch_deg=5.0)),
                                   ("fisheye", (32, 32), dict(yaw_deg=0.0)),
                                   ("equirect", (48, 24), dict(yaw_deg=0.0))]:
        image = earth.render(w, h, camera, unit="relative", sun_disc=False, sun_elevation_deg=25.0,
                             sun_azimuth_deg=0.0, night_sky=False, **kwargs)
        directions = atmo.camera_directions(w, h, camera, **kwargs)
        batch = earth.radiance_batch(0.0, 65.0, directions, ground=True)
        expected = batch * earth.solar_irradiance.astype(np.float32)
        np.testing.assert_array_equal(image, expected)


def test_luminance_frame_agrees_with_sampled_luminance(earth):
    # The frame folds the channels into linear sRGB in float (RenderViewFolded); its luminance
    # (Rec.709 Y) at each pixel is the sampled luminance of that direction in double, to the float
    # kernel's rounding and the fold's 3-channel colour weights: well within 1e-4 relative.
    w, h = 48, 24
    image = earth.render(w, h, "equirect", unit="luminance", sun_disc=False, ground=False, yaw_deg=0.0,
                         sun_elevation_deg=30.0, sun_azimuth_deg=0.0)
    d = atmo.camera_directions(w, h, "equirect", yaw_deg=0.0)
    view_zenith = np.degrees(np.arccos(np.clip(d[..., 2], -1.0, 1.0)))
    azimuth = np.degrees(np.arctan2(d[..., 0], d[..., 1]))  # compass: x east, y north
    sampled = earth.sample(0.0, 60.0, view_zenith, azimuth, unit="luminance").radiance[..., 0]
    y = 0.2126 * image[..., 0] + 0.7152 * image[..., 1] + 0.0722 * image[..., 2]
    sky = view_zenith < 89.0
    np.testing.assert_allclose(y[sky], sampled[sky], rtol=1e-4)


def test_sun_disc_adds_the_transmitted_solar_irradiance(earth):
    # The pixel-integrated disc: sum over pixels of (with - without disc) x pixel solid angle is
    # the sun's irradiance through the atmosphere, T(sun) x solar_irradiance (relative units).
    w, h = 1024, 512
    kwargs = dict(unit="relative", sun_elevation_deg=40.0, sun_azimuth_deg=0.0, yaw_deg=0.0, ground=False)
    with_disc = earth.render(w, h, "equirect", sun_disc=True, **kwargs).astype(np.float64)
    without = earth.render(w, h, "equirect", sun_disc=False, **kwargs).astype(np.float64)
    latitude = np.pi / 2 - (np.arange(h) + 0.5) * np.pi / h
    solid_angle = (2 * np.pi / w) * (np.pi / h) * np.cos(latitude)
    irradiance = ((with_disc - without) * solid_angle[:, None, None]).sum(axis=(0, 1))
    t_sun = earth.sample(0.0, 50.0, 50.0, 0.0).transmittance
    np.testing.assert_allclose(irradiance, t_sun * earth.solar_irradiance, rtol=0.02)


def test_fisheye_has_alpha_and_black_corners(earth):
    frame = earth.render(32, 32, "fisheye", full=True)
    assert frame.alpha is not None and frame.alpha.shape == (32, 32)
    corner = frame.alpha == 0.0
    assert corner[0, 0] and not corner[16, 16]
    np.testing.assert_array_equal(frame.image[corner], 0.0)


def test_spectral_frames(cli):
    model = atmo.Model("hillaire", preset="earth", spectral=12)
    radiance = model.render(32, 16, "equirect", unit="radiance")
    assert radiance.shape == (16, 32, 12)
    colour = model.render(32, 16, "equirect", unit="luminance")
    assert colour.shape == (16, 32, 3)
    xyz = model.render(32, 16, "equirect", unit="luminance", xyz=True, full=True)
    assert xyz.channel_names == ("X", "Y", "Z") and xyz.colour_space == "xyz"
    # Y of the XYZ frame is the luminance of the sRGB frame.
    y = 0.2126 * colour[..., 0] + 0.7152 * colour[..., 1] + 0.0722 * colour[..., 2]
    np.testing.assert_allclose(xyz.image[..., 1], y, rtol=1e-4, atol=1e-3)


@pytest.mark.parametrize("cli_args,model_kwargs,render_kwargs", [
    (["--camera", "equirect", "--width", "64", "--height", "32", "--sun-elevation", "15", "--sun-azimuth", "200"],
     {}, dict(width=64, height=32, camera="equirect", sun_elevation_deg=15.0, sun_azimuth_deg=200.0)),
    (["--camera", "fisheye", "--width", "40", "--height", "40", "--sun-elevation", "5", "--xyz"],
     {}, dict(width=40, height=40, camera="fisheye", sun_elevation_deg=5.0, xyz=True)),
    (["--camera", "cubemap", "--face-size", "12", "--no-ground"],
     {}, dict(width=12, camera="cubemap", ground=False)),
    (["--spectral", "8", "--unit", "radiance", "--width", "48", "--height", "27", "--pitch", "-5", "--fov", "60",
      "--altitude", "3000"],
     dict(spectral=8), dict(width=48, height=27, unit="radiance", pitch_deg=-5.0, fov_deg=60.0, altitude_m=3000.0)),
    (["--unit", "relative", "--width", "32", "--height", "18", "--yaw", "90", "--no-sun-disc"],
     {}, dict(width=32, height=18, unit="relative", yaw_deg=90.0, sun_disc=False)),
])
def test_render_matches_atmo_render_exr(tmp_path, cli, cli_args, model_kwargs, render_kwargs):
    # The frame `atmo render` writes into its EXR, bit for bit: the same library calls.
    exr = tmp_path / "cli.exr"
    cli("render", "--model", "hillaire", "--preset", "earth", *cli_args, "--exr", str(exr), "--no-png")
    printed, printed_alpha, names, metadata = atmo.read_exr(exr)
    frame = atmo.Model("hillaire", preset="earth", **model_kwargs).render(full=True, **render_kwargs)
    assert names == frame.channel_names
    assert metadata["atmo:unit"] == render_kwargs.get("unit", "luminance")
    np.testing.assert_array_equal(frame.image, printed)
    if frame.alpha is not None:
        np.testing.assert_array_equal(frame.alpha, printed_alpha)


def test_monte_carlo_frame_has_standard_errors_that_fall_as_one_over_root_n():
    # Model reference renders progressively; its standard errors come with the frame, and four
    # times the paths halve them (on average over the sky pixels, to Monte Carlo noise).
    model = atmo.Model("reference", preset="earth", seed=2)
    few = model.render(8, 4, "equirect", unit="relative", sun_elevation_deg=30.0, spp=64, full=True)
    many = model.render(8, 4, "equirect", unit="relative", sun_elevation_deg=30.0, spp=256, full=True)
    assert few.image.shape == (4, 8, 3) and few.standard_error.shape == (4, 8, 3)
    sky = slice(0, 2)  # the upper half: sky, lit by the sun
    assert np.all(many.image[sky] > 0.0)
    ratio = many.standard_error[sky].mean() / few.standard_error[sky].mean()
    assert 0.4 < ratio < 0.6
    # The estimates agree within their errors: |difference| < 5 sigma nearly everywhere.
    sigma = np.sqrt(few.standard_error[sky] ** 2 + many.standard_error[sky] ** 2)
    assert np.mean(np.abs(few.image[sky] - many.image[sky]) < 5 * sigma + 1e-12) > 0.95


def test_monte_carlo_frame_matches_atmo_render_with_its_seed(tmp_path, cli):
    # The reference frame depends only on the seed, the pixel's direction and the path count: the
    # module's frame (luminance, from the model of unit solar irradiance) is the CLI's, and so
    # are the standard-error channels of the EXR.
    exr = tmp_path / "mc.exr"
    cli("render", "--preset", "earth", "--model", "reference", "--seed", "5", "--spp", "8", "--camera", "equirect", "--width", "8",
        "--height", "4", "--exr", str(exr), "--no-png")
    printed, _, names, _ = atmo.read_exr(exr)
    frame = atmo.Model("reference", preset="earth", seed=5).render(8, 4, "equirect", spp=8, full=True)
    assert names == ("R", "G", "B", "stderr.R", "stderr.G", "stderr.B")
    np.testing.assert_array_equal(frame.image, printed[..., :3])
    np.testing.assert_array_equal(frame.standard_error, printed[..., 3:])
    frame.write_exr(tmp_path / "module.exr")
    again, _, again_names, _ = atmo.read_exr(tmp_path / "module.exr")
    assert again_names == names
    np.testing.assert_array_equal(again, printed)


def test_target_fixes_the_equirect_in_the_programs_frame(earth):
    """target= gives the CLI's --target equirect: yaw at the program's centre, whatever the sun."""
    names = [t["name"] for t in atmo.engine_targets()]
    assert "three" in names and "blender" in names
    three = next(t for t in atmo.engine_targets() if t["name"] == "three")
    frame = earth.render(64, camera=None, target="three", sun_azimuth_deg=200.0, full=True)
    assert frame.image.shape == (32, 64, 3)
    assert frame.metadata["atmo:camera"] == "equirect"
    assert frame.metadata["atmo:target"] == "three"
    assert float(frame.metadata["atmo:cameraYawDeg"]) == three["equirect_centre_azimuth_deg"]
    same = earth.render(64, camera="equirect", yaw_deg=three["equirect_centre_azimuth_deg"], sun_azimuth_deg=200.0)
    np.testing.assert_array_equal(frame.image, same)
    with pytest.raises(ValueError, match="unknown target 'maya'"):
        earth.render(64, target="maya")
    with pytest.raises(ValueError, match="writes an equirect"):
        earth.render(64, camera="fisheye", target="three")


def test_illuminance_is_the_clis(cli):
    """Model.illuminance gives `atmo illuminance`'s row (printed to 6 digits)."""
    from conftest import parse_csv
    model = atmo.Model("hillaire", preset="earth-spectral")
    row = parse_csv(cli("illuminance", "--model", "hillaire", "--preset", "earth-spectral", "--sun-elevation", "25"))[0]
    e = model.illuminance(25.0)
    for key in ("direct_normal_lux", "diffuse_horizontal_lux", "global_horizontal_lux", "direct_normal_w_m2",
                "diffuse_horizontal_w_m2", "night_sky_horizontal_lux", "night_sky_horizontal_w_m2"):
        assert e[key] == pytest.approx(row[key], rel=1e-5), key
    assert e["global_horizontal_lux"] == pytest.approx(e["diffuse_horizontal_lux"] + e["direct_horizontal_lux"])
    night = model.illuminance(-20.0)
    assert night["direct_normal_lux"] == 0.0 and night["global_horizontal_lux"] < 1e-2
    # The night sky's own light (docs/night.md): most of what is left with the sun 30 degrees down.
    dark = model.illuminance(-30.0)
    assert 4e-4 < dark["night_sky_horizontal_lux"] < 1.5e-3
    assert dark["global_horizontal_lux"] == pytest.approx(dark["diffuse_horizontal_lux"] + dark["night_sky_horizontal_lux"])
    assert model.illuminance(-30.0, night_sky=False)["night_sky_horizontal_lux"] == 0.0


def test_moon_is_the_clis(cli):
    """A moon by hand: the same illuminance as `atmo illuminance --moon-elevation ...`, and a render
    that shows it; a moon without its phase is refused."""
    from conftest import parse_csv
    model = atmo.Model("hillaire", preset="earth")
    e = model.illuminance(-30.0, moon_elevation_deg=60.0, moon_phase_deg=0.0)
    row = parse_csv(cli("illuminance", "--model", "hillaire", "--preset", "earth", "--sun-elevation", "-30", "--moon-elevation", "60", "--moon-phase", "0"))[0]
    for key in ("moon_direct_horizontal_lux", "moon_diffuse_horizontal_lux", "global_horizontal_lux"):
        assert e[key] == pytest.approx(row[key], rel=1e-5), key
    assert 0.17 < e["moon_direct_horizontal_lux"] + e["moon_diffuse_horizontal_lux"] < 0.33
    lit = model.render(32, camera="fisheye", sun_elevation_deg=-30.0, moon_elevation_deg=40.0, moon_phase_deg=20.0)
    dark = model.render(32, camera="fisheye", sun_elevation_deg=-30.0)
    assert float(lit.sum()) > 10.0 * float(dark.sum())
    with pytest.raises(ValueError):
        model.render(32, camera="fisheye", sun_elevation_deg=-30.0, moon_elevation_deg=40.0)


def test_reference_traces_the_moon():
    """Model reference renders a moon by hand (its own paths lit from the moon): the moonlit sky
    is that of a deterministic model within the path tracer's noise, and far brighter than none."""
    kwargs = dict(camera="fisheye", sun_elevation_deg=-30.0, sun_disc=False)
    moon = dict(moon_elevation_deg=40.0, moon_azimuth_deg=100.0, moon_phase_deg=20.0)
    traced = atmo.Model("reference", preset="earth", seed=3).render(16, spp=32, **kwargs, **moon)
    dark = atmo.Model("reference", preset="earth", seed=3).render(16, spp=32, **kwargs)
    scattered = atmo.Model("source4d", preset="earth").render(16, **kwargs, **moon)
    assert float(traced.sum()) > 4.0 * float(dark.sum())
    assert float(traced.sum()) == pytest.approx(float(scattered.sum()), rel=0.05)


def test_moon_of_a_date_is_the_clis(cli):
    """The moon of a date through moon_position (its place, phase and distance) lights the ground as
    `atmo illuminance --date` says; its distance enters as 1/d^2."""
    from conftest import parse_csv
    date, lat, lon = "2026-12-24T22:00+01:00", 46.5, 7.9
    sun = atmo.sun_position(date, lat, lon)
    moon = atmo.moon_position(date, lat, lon)
    model = atmo.Model("hillaire", preset="earth")
    kwargs = dict(moon_elevation_deg=moon["elevation_deg"], moon_azimuth_deg=moon["azimuth_deg"],
                  moon_phase_deg=moon["phase_angle_deg"])
    e = model.illuminance(sun["elevation_deg"], moon_distance_km=moon["distance_km"], **kwargs)
    row = parse_csv(cli("illuminance", "--model", "hillaire", "--preset", "earth", "--date", date, "--latitude", str(lat), "--longitude", str(lon)))[0]
    assert e["moon_direct_horizontal_lux"] == pytest.approx(row["moon_direct_horizontal_lux"], rel=2e-3)
    near = model.illuminance(sun["elevation_deg"], moon_distance_km=360000.0, **kwargs)
    far = model.illuminance(sun["elevation_deg"], moon_distance_km=400000.0, **kwargs)
    assert near["moon_direct_horizontal_lux"] / far["moon_direct_horizontal_lux"] == pytest.approx((400 / 360) ** 2,
                                                                                                  rel=1e-6)
    with pytest.raises(ValueError):
        model.illuminance(-30.0, moon_distance_km=-1.0, **kwargs)


def test_moon_position_is_the_one_render_date_uses(cli):
    """moon_position gives the moon `atmo illuminance --date` prints (its elevation and phase)."""
    from conftest import parse_csv
    date = "2026-12-24T22:00+01:00"
    moon = atmo.moon_position(date, 46.5, 7.9)
    row = parse_csv(cli("illuminance", "--model", "hillaire", "--preset", "earth", "--date", date, "--latitude", "46.5", "--longitude", "7.9"))[0]
    assert moon["elevation_deg"] == pytest.approx(row["moon_elevation_deg"], abs=1e-4)
    assert moon["phase_angle_deg"] == pytest.approx(row["moon_phase_deg"], abs=1e-4)
    assert moon["phase_angle_deg"] < 20.0  # the evening after the full moon of 2026-12-24 01:28 UTC
    assert 350000 < moon["distance_km"] < 410000


def test_night_sky_is_in_renders_as_in_the_clis(cli, tmp_path):
    """render adds the night sky as `atmo render` does; night_sky=False is --no-night-glow."""
    model = atmo.Model("hillaire", preset="earth")
    lit = model.render(128, camera="fisheye", sun_elevation_deg=-30.0)
    dark = model.render(128, camera="fisheye", sun_elevation_deg=-30.0, night_sky=False)
    # Sunlight scattered several times through air lit far away (hillaire's gathered orders):
    # up to 8.7e-11 cd/m^2, against the night sky's 1e-4.
    assert float(dark.max()) < 1e-9
    # The diffuse sky next to the zenith, in a pixel of 2 square degrees (one of a 32-pixel fisheye
    # holds 32 and some 20 catalogue stars, whose light the published dark-sky values leave out):
    # 2.64e-4 cd/m^2 (2026-12-04, with the integrated starlight).
    zenith = lit[64, 64]
    luminance = 0.2126 * zenith[0] + 0.7152 * zenith[1] + 0.0722 * zenith[2]
    assert 1.2e-4 < luminance < 2.7e-4  # the published dark sky (tests/night_sky_test.cc)


def test_sun_position_is_where_render_date_puts_the_sun(cli, tmp_path):
    """sun_position(date, lat, lon) equals the sun `atmo render --date` records."""
    date, lat, lon = "2026-06-21T07:30:00+02:00", 48.85, 2.35
    cli("render", "--model", "hillaire", "--preset", "earth", "--date", date, "--latitude", str(lat), "--longitude", str(lon), "--width", "4", "--height", "4",
        "--no-png", "--exr", str(tmp_path / "s.exr"))
    _, _, _, metadata = atmo.read_exr(tmp_path / "s.exr")
    sun = atmo.sun_position(date, lat, lon)
    assert sun["elevation_deg"] == pytest.approx(float(metadata["atmo:sunElevationDeg"]), rel=1e-9)
    assert sun["azimuth_deg"] == pytest.approx(float(metadata["atmo:sunAzimuthDeg"]), rel=1e-9)
    # On a midsummer morning in Paris the sun is low, north of east.
    assert 5.0 < sun["elevation_deg"] < 25.0 and 45.0 < sun["azimuth_deg"] < 90.0
    assert sun["declination_deg"] == pytest.approx(23.44, abs=0.01)
    refracted = atmo.sun_position(date, lat, lon, refraction=True)
    assert refracted["elevation_deg"] > refracted["geometric_elevation_deg"]
    with pytest.raises(ValueError):
        atmo.sun_position("not a date", lat, lon)
    with pytest.raises(ValueError):
        atmo.sun_position(date, 91.0, lon)


def test_cube_map_products_are_the_clis(cli, tmp_path):
    """write_ktx2, spherical_harmonics, irradiance_cubemap and specular_cubemaps of a rendered cube
    give what `atmo render --camera cubemap --ktx2 --sh --irradiance --specular` writes."""
    import json
    import struct
    flags = ["--camera", "cubemap", "--face-size", "16", "--sun-elevation", "25", "--sun-azimuth", "140"]
    cli("render", "--model", "hillaire", "--preset", "earth", *flags, "--exr", str(tmp_path / "c.exr"), "--png", "", "--ktx2", str(tmp_path / "c.ktx2"), "--mips",
        "--sh", str(tmp_path / "sh.json"), "--irradiance", str(tmp_path / "irr.exr"),
        "--specular", str(tmp_path / "spec.ktx2"), "--specular-levels", "4")
    cube = atmo.Model("hillaire", preset="earth").render(16, camera="cubemap", sun_elevation_deg=25, sun_azimuth_deg=140)
    exr, _, _, _ = atmo.read_exr(tmp_path / "c.exr")
    np.testing.assert_array_equal(cube, exr)

    sh = atmo.spherical_harmonics(cube)
    written = json.loads((tmp_path / "sh.json").read_text())
    assert sh["radiance"].shape == (9, 3)
    for frame in ("enu", "y_up"):
        ours = atmo.spherical_harmonics(cube, frame=frame)
        np.testing.assert_allclose(ours["radiance"], written[frame]["radiance_coefficients"], rtol=1e-9)
        np.testing.assert_allclose(ours["irradiance"], written[frame]["irradiance_coefficients"], rtol=1e-9)
    # Facing up the irradiance of the L2 SH (enu: z up) is sum E_lm Y_lm(up).
    up = np.array([0.282095, 0.0, 0.488603, 0.0, 0.0, 0.0, 0.315392 * 2.0, 0.0, 0.0])
    assert np.all(up @ sh["irradiance"] > 0.0)

    irradiance = atmo.irradiance_cubemap(cube)
    written_irradiance, _, _, _ = atmo.read_exr(tmp_path / "irr.exr")
    np.testing.assert_allclose(irradiance, written_irradiance, rtol=1e-6)

    levels = atmo.specular_cubemaps(cube, levels=4)
    assert [level.shape[1] for level in levels] == [16, 8, 4, 2]
    np.testing.assert_array_equal(levels[0], cube)  # roughness 0 is the radiance itself

    # KTX2 files: Python's and the CLI's have the same header fields and level sizes.
    for name, ours in (("c.ktx2", lambda p: atmo.write_ktx2(p, cube, mips=True)),
                       ("spec.ktx2", lambda p: atmo.write_ktx2(p, levels))):
        ours(tmp_path / ("py_" + name))
        a, b = (tmp_path / name).read_bytes(), (tmp_path / ("py_" + name)).read_bytes()
        assert a[:12] == b[:12] == b"\xabKTX 20\xbb\r\n\x1a\n"
        # vkFormat, typeSize, width, height, depth, layers, faces, levels, supercompression
        assert struct.unpack_from("<9I", a, 12) == struct.unpack_from("<9I", b, 12)
        assert struct.unpack_from("<9I", a, 12)[6] == 6
    with pytest.raises(ValueError, match="6 N high"):
        atmo.irradiance_cubemap(np.ones((10, 4, 3), np.float32))


def test_export_tables_is_atmo_precompute(cli, tmp_path):
    """Model.export_tables writes the tables `atmo precompute --out` writes, byte for byte."""
    cli("precompute", "--model", "hillaire", "--sun-elevation", "15", "--out", str(tmp_path / "cli"))
    written = atmo.Model("hillaire", preset="earth").export_tables(tmp_path / "py", sun_elevation_deg=15.0)
    assert [p.rsplit("/", 1)[-1] for p in written][-1] == "py.json"
    raws = [p for p in written if p.endswith(".raw")]
    assert len(raws) == 6
    for raw in raws:
        suffix = raw.rsplit("/py", 1)[-1]
        assert (tmp_path / ("cli" + suffix)).read_bytes() == open(raw, "rb").read(), suffix
    with pytest.raises(ValueError, match="model simple has none"):
        atmo.Model("simple", preset="simple").export_tables(tmp_path / "s")


def test_write_hdr_is_the_clis_face(cli, tmp_path):
    """write_hdr writes the bytes `atmo render --hdr-faces` writes for the same face."""
    cli("render", "--model", "hillaire", "--preset", "earth", "--camera", "cubemap", "--face-size", "8", "--sun-elevation", "30", "--hdr-faces",
        str(tmp_path / "c"), "--exr", str(tmp_path / "c.exr"), "--png", "")
    cube = atmo.Model("hillaire", preset="earth").render(8, camera="cubemap", sun_elevation_deg=30)
    exr, _, _, _ = atmo.read_exr(tmp_path / "c.exr")
    np.testing.assert_array_equal(cube, exr)
    # Face +Y of the OpenEXR layout is the view from inside; the HDR face is the GL-convention
    # one, flipped top-bottom for the Y faces (docs/environment.md): rows reversed.
    atmo.write_hdr(tmp_path / "py.hdr", cube[16:24][::-1])
    assert (tmp_path / "py.hdr").read_bytes() == (tmp_path / "c_py.hdr").read_bytes()
    with pytest.raises(ValueError, match="3-channel"):
        atmo.write_hdr(tmp_path / "x.hdr", np.ones((2, 2, 4), np.float32))


def test_cube_faces_for_three_are_the_clis(cli, tmp_path):
    """cube_faces_for_three + write_hdr give the files of --target three --hdr-faces."""
    cli("render", "--model", "hillaire", "--preset", "earth", "--camera", "cubemap", "--face-size", "8", "--sun-elevation", "30", "--sun-azimuth", "70",
        "--target", "three", "--hdr-faces", str(tmp_path / "c"), "--exr", "", "--png", "")
    cube = atmo.Model("hillaire", preset="earth").render(8, camera="cubemap", sun_elevation_deg=30, sun_azimuth_deg=70)
    faces = atmo.cube_faces_for_three(cube)
    assert len(faces) == 6
    for name, face in zip(("px", "nx", "py", "ny", "pz", "nz"), faces):
        atmo.write_hdr(tmp_path / f"py_{name}.hdr", face)
        assert (tmp_path / f"py_{name}.hdr").read_bytes() == (tmp_path / f"c_{name}.hdr").read_bytes(), name
