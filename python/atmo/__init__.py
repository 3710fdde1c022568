"""atmo: physically based sky and atmosphere models from Python (docs/python.md).

    import atmo, numpy as np
    m = atmo.Model("hillaire", preset="earth")
    r = m.sample(0.0, 60.0, np.linspace(0, 90, 91), 90.0)   # NumPy broadcasting
    r.radiance.shape, r.transmittance.shape                  # (91, 3): per channel
    img = m.render(512, 256, camera="equirect", sun_elevation_deg=20)   # float32 H x W x 3, cd/m^2
    atmo.write_exr("env.exr", img)
    atmo.write_png("env.png", img)

The quantities are those of the command line: `Model.sample` gives what `atmo sample` prints
(radiance in sr^-1 per unit solar irradiance, the transmittance to the top of the atmosphere, the
standard error of Monte Carlo estimates), `Model.render` what `atmo render` writes into its EXR.
Errors in the input raise ValueError with atmo's one-line message.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from . import _atmo

__all__ = [
    "Model",
    "moon_position",
    "SampleResult",
    "Frame",
    "write_exr",
    "read_exr",
    "write_png",
    "auto_exposure_ev100",
    "exposure_from_ev100",
    "engine_targets",
    "write_hdr",
    "cube_faces_for_three",
    "write_ktx2",
    "spherical_harmonics",
    "irradiance_cubemap",
    "specular_cubemaps",
    "sun_position",
    "camera_directions",
    "sun_direction",
    "model_names",
    "set_threads",
    "set_table_cache",
    "table_cache",
    "default_table_cache",
    "preset_names",
    "preset",
    "aerosol_types",
    "set_max_memory",
    "max_memory",
    "irradiance",
    "calibrate",
    "read_epw",
    "with_aerosol",
    "annual",
    "annual_on_dask",
    "CAMERAS",
    "UNITS",
]

__version__ = _atmo.version
CAMERAS = ("perspective", "fisheye", "equirect", "cubemap")
UNITS = ("relative", "radiance", "luminance")



# The moon's mean distance (km), the photometric model's reference (include/atmo/moon.h).
MOON_REFERENCE_DISTANCE_KM = 384400.0


def _moon_arguments(elevation, azimuth, phase, distance=None):
    """The moon's three angles and its distance for the C++ side: NaN where an angle is not given,
    the reference distance where the distance is not."""
    nan = float("nan")
    if distance is not None and not (float(distance) > 0.0 and math.isfinite(float(distance))):
        raise ValueError(f"moon_distance_km must be a positive number (got {distance!r})")
    return (nan if elevation is None else float(elevation), nan if azimuth is None else float(azimuth),
            nan if phase is None else float(phase),
            MOON_REFERENCE_DISTANCE_KM if distance is None else float(distance))

def _option_text(key: str, value) -> str:
    """A model option as the KEY=VALUE text of `--option`: booleans as on/off, floats exactly."""
    if isinstance(value, (bool, np.bool_)):
        return "on" if value else "off"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, str):
        return value
    raise ValueError(f"option {key}: expected a string, number or bool, got {type(value).__name__}")


@dataclass(frozen=True)
class SampleResult:
    """What `Model.sample` returns: arrays of shape (..., channels), in the unit asked for.

    radiance: relative (sr^-1 per unit solar irradiance), spectral radiance (W m^-2 sr^-1 nm^-1)
      or luminance (cd/m^2, one channel); transmittance: unitless, to the top of the atmosphere
      (luminous for unit luminance), 0 where the ray meets the ground; standard_error: of the
      radiance, 0 for deterministic models.
    """

    radiance: np.ndarray
    transmittance: np.ndarray
    standard_error: np.ndarray
    channel_names: tuple
    wavelengths_nm: tuple
    unit: str


@dataclass(frozen=True)
class Frame:
    """The extras of `Model.render(..., full=True)`: the image and how to write it."""

    image: np.ndarray  # float32 H x W x C
    alpha: Optional[np.ndarray]  # float32 H x W (fisheye), else None
    channel_names: tuple
    colour_space: str  # "linear_srgb", "xyz" or "" (per-channel values)
    envmap: str  # "latlong", "cube" or ""
    standard_error: Optional[np.ndarray]  # Monte Carlo models: float32 H x W x C, else None
    metadata: dict

    def write_exr(self, path: Union[str, os.PathLike]) -> None:
        """The frame as `atmo render` writes its EXR (with the standard-error channels of a Monte
        Carlo frame)."""
        image, names = self.image, list(self.channel_names)
        if self.standard_error is not None:
            image = np.concatenate([image, self.standard_error], axis=-1)
            names += ["stderr." + n for n in self.channel_names]
        write_exr(path, image, alpha=self.alpha, channel_names=names, colour_space=self.colour_space,
                  envmap=self.envmap, metadata=self.metadata)

    def write_png(self, path: Union[str, os.PathLike], **mapping) -> None:
        """The frame tone-mapped (see `write_png`); needs a colour frame (3 channels)."""
        write_png(path, self.image, alpha=self.alpha, **mapping)


class Model:
    """A sky model with its precomputed tables.

    Model()                                             # source4d on us-standard, as `atmo render`
    Model(name="hillaire", preset="earth")            # a preset (atmo.preset_names())
    Model("elek", config="my.json")                     # a JSON file as `atmo --config`
    Model("hillaire", config={"preset": "earth", "mie": {"phase_g": 0.7}})   # a dict: the same JSON
    Model("hillaire", options={"sky_view": "off"})      # `--option KEY=VALUE`
    Model("hillaire", preset="earth", spectral=16)      # `--spectral 16`: 16 wavelengths
    Model("source4d", preset="us-standard", wavelengths=[755, 765, 775])   # `--wavelengths 755,765,775`
    Model("reference", options={"samples": 4096}, seed=1)
    Model("source4d", preset="us-standard", aerosol="urban", aod=0.4)   # `--aerosol urban --aod 0.4`

    The aerosol keywords are the command line's knobs (docs/aerosols.md), applied after `spectral`:
    aerosol (an OPAC type, atmo.aerosol_types()), aod (tau at 550 nm), angstrom, visibility (km),
    turbidity (Linke) and aerosol_phase ("opac", the default, or "henyey-greenstein", `--aerosol-phase`); at most
    one of aod, visibility and turbidity.
    """

    def __init__(self, name: str = "source4d", preset: Optional[str] = None,
                 config: Union[None, str, os.PathLike, Mapping] = None,
                 options: Optional[Mapping[str, object]] = None, spectral: int = 0,
                 seed: Optional[int] = None, aerosol: Optional[str] = None, aod: Optional[float] = None,
                 angstrom: Optional[float] = None, visibility: Optional[float] = None,
                 turbidity: Optional[float] = None, wavelengths: Optional[Sequence[float]] = None,
                 aerosol_phase: Optional[str] = None):
        if preset is not None and config is not None:
            raise ValueError("give preset or config, not both")
        config_path = config_json = None
        if isinstance(config, Mapping):
            config_json = json.dumps(config)
        elif config is not None:
            config_path = os.fspath(config)
        elif preset is None:
            preset = "us-standard"
        if isinstance(spectral, bool) or not isinstance(spectral, (int, np.integer)):
            raise ValueError(f"spectral must be an integer (got {spectral!r})")
        if spectral != 0 and not 3 <= spectral <= 256:
            raise ValueError(f"spectral {spectral}: the wavelength count must be in [3, 256]")
        wavelength_list = []
        if wavelengths is not None:
            if spectral != 0:
                raise ValueError("give spectral or wavelengths, not both")
            array = np.asarray(wavelengths)
            if array.ndim != 1 or array.size == 0 or not np.issubdtype(array.dtype, np.number) or \
                    np.iscomplexobj(array):
                raise ValueError(f"wavelengths must be a non-empty sequence of numbers in nm (got {wavelengths!r})")
            wavelength_list = [float(x) for x in array]
        texts = {}
        for key, value in (options or {}).items():
            texts[str(key)] = _option_text(str(key), value)
        if seed is not None:
            if "seed" in texts:
                raise ValueError("give the seed once: seed= or options['seed']")
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
                raise ValueError(f"seed must be an integer in [0, 2^64 - 1] (got {seed!r})")
            texts["seed"] = str(int(seed))
        knobs = {}
        for key, value in (("aod", aod), ("angstrom", angstrom), ("visibility", visibility), ("turbidity", turbidity)):
            if value is not None:
                if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                    raise ValueError(f"{key} must be a number (got {value!r})")
                knobs[key] = float(value)
        if aerosol is not None and not isinstance(aerosol, str):
            raise ValueError(f"aerosol must be a type name (got {aerosol!r})")
        if aerosol_phase is not None and not isinstance(aerosol_phase, str):
            raise ValueError(f"aerosol_phase must be 'henyey-greenstein' or 'opac' (got {aerosol_phase!r})")
        self._model = _atmo.Model(name, preset, config_path, config_json, int(spectral), texts, aerosol=aerosol,
                                  wavelengths=wavelength_list, aerosol_phase=aerosol_phase, **knobs)
        self._options = dict(texts)

    # --- what the model is ---------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self._model.name

    @property
    def preset(self) -> str:
        """The preset the parameters came from ("custom" for a config without one)."""
        return self._model.preset

    @property
    def channel_count(self) -> int:
        return self._model.channel_count

    @property
    def wavelengths_nm(self) -> np.ndarray:
        """The wavelength of each channel, nm."""
        return np.asarray(self._model.wavelengths_nm)

    @property
    def channel_names(self) -> tuple:
        """R, G, B for 3 channels (as the EXR names them), else the wavelengths ("550nm")."""
        if self.channel_count == 3:
            return ("R", "G", "B")
        return tuple(f"{w:g}nm" for w in self._model.wavelengths_nm)

    @property
    def solar_irradiance(self) -> np.ndarray:
        """The preset's per-channel solar irradiance that relative images are multiplied by."""
        return np.asarray(self._model.solar_irradiance)

    @property
    def solar_spectral_irradiance(self) -> np.ndarray:
        """The solar spectral irradiance at each channel's wavelength, W m^-2 nm^-1."""
        return np.asarray(self._model.solar_spectral_irradiance)

    @property
    def exposure(self) -> float:
        """The preset's display exposure (`atmo render`'s PNG default for a relative RGB frame)."""
        return self._model.exposure

    @property
    def observer_altitude_m(self) -> float:
        return self._model.observer_altitude_m

    @property
    def top_altitude_m(self) -> float:
        """Altitude of the top of the atmosphere above the ground, m."""
        return self._model.top_altitude_m

    @property
    def monte_carlo(self) -> bool:
        return self._model.monte_carlo

    @property
    def options(self) -> dict:
        return dict(self._options)

    def parameters(self) -> dict:
        """The atmosphere as the JSON of docs/parameters.md (`atmo presets --dump`)."""
        return json.loads(self._model.parameters_json())

    def __repr__(self) -> str:
        return f"atmo.Model({self.name!r}, preset={self.preset!r}, channels={self.channel_count})"

    # --- queries -------------------------------------------------------------------------------
    def sample(self, altitude_m, sun_zenith_deg, view_zenith_deg, azimuth_deg, unit: str = "relative",
               dtype=np.float64) -> SampleResult:
        """Radiance, transmittance and standard error, as `atmo sample` computes them.

        The four arguments are scalars or arrays, broadcast together with NumPy's rules; the
        results have shape broadcast_shape + (channels,). Angles in degrees: the sun at compass
        azimuth 0, the view at `azimuth_deg` (the azimuth between view and sun). `unit`:
        "relative" (sr^-1 per unit solar irradiance, per channel), "radiance" (W m^-2 sr^-1 nm^-1
        per channel) or "luminance" (cd/m^2, one channel; the transmittance is the luminous one).
        Points that share an altitude and sun zenith share one view of the model.
        """
        if unit not in UNITS:
            raise ValueError(f"unknown unit '{unit}' (use relative, radiance or luminance)")
        dtype = np.dtype(dtype)
        if dtype not in (np.float64, np.float32):
            raise ValueError(f"dtype must be float64 or float32 (got {dtype})")
        inputs = (altitude_m, sun_zenith_deg, view_zenith_deg, azimuth_deg)
        try:
            shape = np.broadcast_shapes(*(np.shape(a) for a in inputs))
        except ValueError as error:
            raise ValueError(f"sample: the arguments do not broadcast together ({error})") from None
        # Bounded before any copy: the four inputs as contiguous doubles and the three results.
        points = int(np.prod(shape, dtype=np.float64))
        needed = points * 8.0 * (4 + 3 * self.channel_count)
        limit = _memory_limit_bytes()
        if needed > limit:
            raise ValueError(f"sample: {points} points ({shape}) need {needed / 2**30:.1f} GiB, more than the "
                             f"{limit / 2**30:.1f} GiB allowed (half of this machine's memory); sample in pieces")
        arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in inputs))
        flat = [np.ascontiguousarray(a).reshape(-1) for a in arrays]
        radiance, transmittance, standard_error = self._model.sample(*flat, unit, list(shape))
        channels = radiance.shape[1]

        def shaped(a):
            return a.reshape(shape + (channels,)).astype(dtype, copy=False)

        luminance = unit == "luminance"
        return SampleResult(
            radiance=shaped(radiance), transmittance=shaped(transmittance),
            standard_error=shaped(standard_error),
            channel_names=("luminance",) if luminance else self.channel_names,
            wavelengths_nm=() if luminance else tuple(self._model.wavelengths_nm), unit=unit)

    def radiance_batch(self, altitude_m: float, sun_zenith_deg: float, directions, sun_disc: bool = False,
                       ground: bool = False) -> np.ndarray:
        """SkyView::RadianceBatch (the renderer's float32 path): directions (..., 3), unit vectors
        in the local frame (x east, y north, z up; 0 vectors give 0), the sun at compass azimuth
        0. Returns float32 (..., channels), relative radiance, plus the sun disc and the lit
        ground when asked."""
        d = np.asarray(directions, dtype=np.float64)
        if d.ndim < 1 or d.shape[-1] != 3:
            raise ValueError("radiance_batch: directions must have shape (..., 3)")
        out = self._model.radiance_batch(float(altitude_m), float(sun_zenith_deg),
                                         np.ascontiguousarray(d.reshape(-1, 3)), bool(sun_disc), bool(ground))
        return out.reshape(d.shape[:-1] + (out.shape[1],))

    # --- images --------------------------------------------------------------------------------
    def export_tables(self, name: Union[str, os.PathLike], *, altitude_m: Optional[float] = None,
                      sun_elevation_deg: float = 10.0, sun_azimuth_deg: float = 180.0) -> list:
        """`atmo precompute --out NAME` for this model: elek's scattering and transmittance tables,
        or hillaire's six tables for one observer and sun (docs/tables.md), as NAME.json and
        NAME*.exr/.raw, each written atomically; the paths written. Other models have no tables."""
        if altitude_m is None:
            altitude_m = self.observer_altitude_m
        return list(self._model.export_tables(os.fspath(name), float(altitude_m), float(sun_elevation_deg),
                                              float(sun_azimuth_deg)))

    def illuminance(self, sun_elevation_deg: float, altitude_m: Optional[float] = None, night_sky: bool = True,
                    moon_elevation_deg: Optional[float] = None, moon_azimuth_deg: Optional[float] = None,
                    moon_phase_deg: Optional[float] = None, moon_distance_km: Optional[float] = None) -> dict:
        """What `atmo illuminance` prints for one sun elevation (include/atmo/illuminance.h): the sun's
        and the sky's light on a horizontal plane, direct_normal_lux, direct_horizontal_lux,
        diffuse_horizontal_lux, global_horizontal_lux, and direct_normal_w_m2 and
        diffuse_horizontal_w_m2 over 360-830 nm; night_sky_horizontal_lux and _w_m2, the night
        sky's own light (docs/night.md), part of the global unless night_sky=False; with a moon
        (moon_elevation_deg and moon_phase_deg; moon_azimuth_deg defaults to opposite the sun, which
        is south; moon_distance_km defaults to the mean 384 400 km), moon_direct_horizontal_lux and
        moon_diffuse_horizontal_lux, also in the global."""
        if altitude_m is None:
            altitude_m = self.observer_altitude_m
        return dict(self._model.illuminance(float(altitude_m), float(sun_elevation_deg), bool(night_sky),
                                            *_moon_arguments(moon_elevation_deg, moon_azimuth_deg, moon_phase_deg,
                                                             moon_distance_km)))

    def render(self, width: int = 1280, height: Optional[int] = None, camera: Optional[str] = None, *,
               fov_deg: float = 90.0, yaw_deg: Optional[float] = None, pitch_deg: float = 10.0,
               sun_elevation_deg: float = 10.0, sun_azimuth_deg: float = 180.0,
               altitude_m: Optional[float] = None, sun_disc: bool = True, ground: bool = True,
               unit: str = "luminance", xyz: bool = False, spp: int = 0, full: bool = False,
               target: Optional[str] = None, night_sky: bool = True,
               moon_elevation_deg: Optional[float] = None, moon_azimuth_deg: Optional[float] = None,
               moon_phase_deg: Optional[float] = None, moon_distance_km: Optional[float] = None):
        """One frame as `atmo render` renders it (same defaults), as a float32 H x W x C array.

        camera: perspective (fov_deg, yaw_deg, pitch_deg), fisheye (all-sky; 0 outside the
        circle), equirect (lat-long environment map) or cubemap (width is the face size; the six
        faces stacked vertically as OpenEXR lays them out, 6 width x width). yaw_deg defaults to
        the sun azimuth (0, north up, for the fisheye). unit: luminance (linear sRGB in cd/m^2, or
        CIE XYZ with xyz=True), radiance (W m^-2 sr^-1 nm^-1 per wavelength) or relative (the
        channels x the preset's solar_irradiance). spp: paths per pixel of a Monte Carlo model.
        With full=True, returns a Frame (alpha, channel names, EXR metadata, standard error).
        target: an equirect as that program reads it, fixed in the world (engine_targets();
        docs/environment.md): camera defaults to equirect and yaw_deg to the program's centre.
        night_sky: add the night sky's own light, airglow and zodiacal light (docs/night.md), as
        `atmo render` does; False is its --no-night-glow.
        moon_elevation_deg, moon_phase_deg (0 full, 180 new) and optionally moon_azimuth_deg
        (default opposite the sun), moon_distance_km (default the mean 384 400 km): a moon by hand,
        its disc and its light through the model, as `atmo render --moon-elevation ...` (every
        model; reference traces its light). The moon of a date and place: pass moon_position's
        elevation_deg, azimuth_deg, phase_angle_deg and distance_km.
        """
        convention = None
        if target is not None:
            convention = next((t for t in engine_targets() if t["name"] == target), None)
            if convention is None:
                raise ValueError(f"unknown target '{target}' (known: {', '.join(t['name'] for t in engine_targets())})")
            if camera not in (None, "equirect"):
                raise ValueError(f"target {target} writes an equirect: use camera='equirect'")
            camera = "equirect"
            if yaw_deg is None:
                yaw_deg = convention["equirect_centre_azimuth_deg"]
        if camera is None:
            camera = "perspective"
        if camera not in CAMERAS:
            raise ValueError(f"unknown camera '{camera}' (use {', '.join(CAMERAS)})")
        if unit not in UNITS:
            raise ValueError(f"unknown unit '{unit}' (use relative, radiance or luminance)")
        for name, value in (("width", width), ("height", height), ("spp", spp)):
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer))):
                raise ValueError(f"{name} must be an integer (got {value!r})")
        if spp < 0:
            raise ValueError(f"spp must be >= 0 (got {spp})")
        if camera == "cubemap":
            if height is not None and height != 6 * width:
                raise ValueError(f"camera cubemap: width is the face size and height 6 x width (got {width}x{height})")
            height = 6 * width
        elif height is None:
            height = {"equirect": max(width // 2, 1), "fisheye": width}.get(camera, max(width * 9 // 16, 1))
        if yaw_deg is None:
            yaw_deg = 0.0 if camera == "fisheye" else sun_azimuth_deg
        if altitude_m is None:
            altitude_m = self.observer_altitude_m
        image, alpha, names, colour_space, envmap, standard_error = self._model.render(
            camera, int(width), int(height), float(fov_deg), float(yaw_deg), float(pitch_deg), float(altitude_m),
            float(sun_elevation_deg), float(sun_azimuth_deg), bool(sun_disc), bool(ground), unit, bool(xyz),
            int(spp), bool(night_sky),
            *_moon_arguments(moon_elevation_deg, moon_azimuth_deg, moon_phase_deg, moon_distance_km))
        if not full:
            return image
        metadata = {
            "atmo:version": __version__,
            "atmo:model": self.name,
            "atmo:backend": "cpu",
            "atmo:preset": self.preset,
            "atmo:parameterHash": self._model.parameter_hash,
            "atmo:unit": unit,
            "atmo:camera": camera,
            "atmo:sunElevationDeg": f"{sun_elevation_deg:.10g}",
            "atmo:sunAzimuthDeg": f"{sun_azimuth_deg:.10g}",
            "atmo:altitudeM": f"{altitude_m:.10g}",
            "atmo:wavelengthsNm": ", ".join(f"{w:.10g}" for w in self._model.wavelengths_nm),
            "atmo:cameraYawDeg": f"{yaw_deg:.10g}",
            "atmo:terms": ("sun_disc " if sun_disc else "") + ("ground" if ground else ""),
            "atmo:modelOptions": " ".join(f"{k}={v}" for k, v in sorted(self._options.items())),
            "atmo:writer": "atmo Python module",
        }
        if camera == "cubemap":
            del metadata["atmo:cameraYawDeg"]  # the faces fix their own directions (as atmo render)
        if convention is not None:
            metadata["atmo:target"] = convention["name"]
            metadata["atmo:targetWorld"] = convention["world"]
        if camera == "perspective":
            metadata["atmo:cameraFovDeg"] = f"{fov_deg:.10g}"
            metadata["atmo:cameraPitchDeg"] = f"{pitch_deg:.10g}"
        return Frame(image=image, alpha=alpha, channel_names=tuple(names), colour_space=colour_space,
                     envmap=envmap, standard_error=standard_error, metadata=metadata)


# --- files -------------------------------------------------------------------------------------
# The command line's largest image side; an OpenEXR cube map stacks six faces of up to that size.
_MAX_IMAGE_SIDE = 16384


def _real_array(values, what: str) -> np.ndarray:
    """values as an array, refused (before any copy to float32) when complex, not numeric or too large."""
    a = np.asarray(values)
    if np.iscomplexobj(a):
        raise ValueError(f"{what} must be real numbers (got {a.dtype})")
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{what} must be numbers (got {a.dtype})")
    if a.ndim >= 2 and (a.shape[0] > 6 * _MAX_IMAGE_SIDE or a.shape[1] > _MAX_IMAGE_SIDE):
        raise ValueError(f"{what} of {a.shape[1]} x {a.shape[0]} pixels is too large: at most {_MAX_IMAGE_SIDE} "
                         f"wide and {6 * _MAX_IMAGE_SIDE} high (a cube map's six faces)")
    return a


def _image_array(image) -> np.ndarray:
    a = _real_array(image, "an image").astype(np.float32, copy=False)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3:
        raise ValueError(f"an image must be an H x W x C (or H x W) array (got shape {a.shape})")
    return np.ascontiguousarray(a)


def _alpha_array(alpha) -> Optional[np.ndarray]:
    return None if alpha is None else np.ascontiguousarray(_real_array(alpha, "alpha").astype(np.float32, copy=False))


def write_exr(path: Union[str, os.PathLike], image, *, alpha=None, channel_names: Optional[Sequence[str]] = None,
              colour_space: Optional[str] = None, envmap: Optional[str] = None,
              metadata: Optional[Mapping[str, str]] = None) -> None:
    """A float32 EXR (ZIP) of an H x W x C array, written atomically (a temporary file renamed over
    the target). channel_names: default R, G, B for 3 channels, else C0..Cn-1; alpha: H x W,
    written as A; colour_space: "linear_srgb" or "xyz" (the chromaticities attribute); envmap:
    "latlong" or "cube"; metadata: string attributes."""
    write_exr_path = os.fspath(path)
    _atmo.write_exr(write_exr_path, _image_array(image), _alpha_array(alpha), list(channel_names or []),
                    colour_space or "", envmap or "",
                    [(str(k), str(v)) for k, v in (metadata or {}).items()])


def read_exr(path: Union[str, os.PathLike]):
    """(image H x W x C float32, alpha H x W or None, channel names, metadata dict) of an EXR."""
    image, alpha, names, metadata = _atmo.read_exr(os.fspath(path))
    return image, alpha, tuple(names), metadata


def write_png(path: Union[str, os.PathLike], image, *, alpha=None, exposure: Optional[float] = None,
              ev100: Optional[float] = None, tonemap: str = "agx", gamma: Optional[float] = None,
              per_channel: bool = False, dither: bool = True, bits: int = 8,
              metering: str = "adaptive") -> None:
    """A tone-mapped PNG of a linear sRGB H x W x 3 array, written atomically, as `atmo render`
    writes it: exposure (a multiplier) or ev100, by default auto-exposure (metering "adaptive" for
    cd/m^2, "camera" for relative values; docs/display.md); tonemap "agx", "exp", "aces" or "none";
    gamma: the bare power instead of the sRGB curve; per_channel: the exp/aces/none curve per
    channel instead of on luminance; 8 or 16 bits."""
    _atmo.write_png(os.fspath(path), _image_array(image), _alpha_array(alpha), exposure, ev100, tonemap, gamma,
                    bool(per_channel), bool(dither), int(bits), str(metering))


# --- cube maps and image-based lighting (include/atmo/cubemap.h, include/atmo/ibl.h) -------------
# A cube map here is what Model.render(N, camera="cubemap") returns: the six faces +X, -X, +Y, -Y,
# +Z, -Z stacked vertically as OpenEXR lays them out (6 N x N x C, linear sRGB for unit
# "luminance"; docs/environment.md).

def write_hdr(path: Union[str, os.PathLike], image) -> None:
    """A Radiance HDR (RGBE) file of a linear H x W x 3 array, as `atmo render --hdr-faces` writes
    its faces (include/atmo/image.h, WriteRadianceHdr); written atomically."""
    _atmo.write_hdr(os.fspath(path), _image_array(image))


def cube_faces_for_three(cube) -> list:
    """The six faces px, nx, py, ny, pz, nz of a rendered cube map as three.js's CubeTexture wants
    them (`--target three --hdr-faces`; docs/environment.md): write each with write_hdr and load
    them with three's HDRCubeTextureLoader."""
    return list(_atmo.cube_faces_for_three(_image_array(cube)))


def write_ktx2(path: Union[str, os.PathLike], cube, *, mips: bool = False, float32: bool = False) -> None:
    """A KTX 2.0 cubemap as `atmo render --ktx2` writes it: cube is one cube map (mips=True adds the
    solid-angle weighted chain down to 1 texel) or a list of levels (specular_cubemaps' result);
    RGBA16F, or RGBA32F with float32. Written atomically."""
    levels = list(cube) if isinstance(cube, (list, tuple)) else [cube]
    _atmo.write_ktx2(os.fspath(path), [_image_array(level) for level in levels], bool(mips), bool(float32))


def spherical_harmonics(cube, frame: str = "enu") -> dict:
    """L2 spherical harmonics of a 3-channel cube map, as `atmo render --sh` computes them:
    {"frame", "radiance": 9 x 3 L_lm, "irradiance": 9 x 3 E_lm = A_l L_lm}, in the frame "enu"
    (x east, y north, z up) or "y_up" (the cube frame: X east, Y up, Z south)."""
    return dict(_atmo.spherical_harmonics(_image_array(cube), str(frame)))


def irradiance_cubemap(cube, size: int = 32, source_size: int = 32) -> np.ndarray:
    """The diffuse irradiance cube map of `atmo render --irradiance` (texel n: E(n), lux for a
    luminance cube), size texels a face, from the radiance filtered to source_size."""
    return _atmo.irradiance_cubemap(_image_array(cube), int(size), int(source_size))


def specular_cubemaps(cube, levels: int = 6, samples: int = 32) -> list:
    """The GGX-prefiltered specular chain of `atmo render --specular`: level m has roughness
    m / (levels - 1) and half the size of the one before; write it with write_ktx2."""
    return list(_atmo.specular_cubemaps(_image_array(cube), int(levels), int(samples)))


def engine_targets() -> list:
    """The programs Model.render(target=...) and `atmo render --target` write equirects for: name,
    program, equirect_centre_azimuth_deg, world, recipe, source
    (include/atmo/engine_target.h)."""
    return [dict(t) for t in _atmo.engine_targets()]


def auto_exposure_ev100(image, alpha=None, metering: str = "adaptive") -> float:
    """The EV100 of `atmo render --auto-exposure` for a linear sRGB image (include/atmo/image.h):
    metering "adaptive" (cd/m^2; a noon sky bright, twilight darker) or "camera" (a mid grey)."""
    return _atmo.auto_exposure_ev100(_image_array(image), _alpha_array(alpha), str(metering))


def exposure_from_ev100(ev100: float) -> float:
    return _atmo.exposure_from_ev100(float(ev100))


def camera_directions(width: int, height: int, camera: str = "perspective", *, fov_deg: float = 90.0,
                      yaw_deg: float = 0.0, pitch_deg: float = 0.0) -> np.ndarray:
    """The unit view direction of each pixel centre of a camera (H x W x 3, x east, y north, z up),
    as the renderer forms them; 0 where it sees nothing (outside a fisheye's circle)."""
    if camera not in CAMERAS[:3]:
        raise ValueError(f"unknown camera '{camera}' (use perspective, fisheye or equirect)")
    return _atmo.camera_directions(camera, int(width), int(height), float(fov_deg), float(yaw_deg),
                                   float(pitch_deg))


def sun_direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit direction towards the sun from its elevation and compass azimuth (degrees)."""
    return np.asarray(_atmo.sun_direction(float(elevation_deg), float(azimuth_deg)))


def sun_position(date: str, latitude_deg: float, longitude_deg: float, *, refraction: bool = False,
                 height_m: float = 0.0) -> dict:
    """The sun at an ISO 8601 instant (`2026-06-21T05:30:00+02:00`; no zone: UTC) for an observer at
    latitude_deg (north positive) and longitude_deg (east positive), as `atmo render --date` places
    it (include/atmo/sun_position.h, libnova): elevation_deg (apparent with refraction=True),
    geometric_elevation_deg, azimuth_deg (compass), right_ascension_deg, declination_deg,
    distance_au, julian_day_utc. Feed elevation and azimuth to Model.render or Model.sample."""
    return dict(_atmo.sun_position(str(date), float(latitude_deg), float(longitude_deg), bool(refraction),
                                   float(height_m)))


def moon_position(date: str, latitude_deg: float, longitude_deg: float) -> dict:
    """The moon at an ISO 8601 instant for an observer at latitude_deg (north positive) and
    longitude_deg (east positive), as `atmo render --date` places it (include/atmo/moon.h,
    libnova's lunar ephemeris with the observer's parallax): elevation_deg (geometric),
    azimuth_deg (compass), phase_angle_deg (0 full, 180 new), distance_km, julian_day_utc. Feed
    them to Model.render or Model.illuminance (moon_elevation_deg=..., moon_azimuth_deg=...,
    moon_phase_deg=..., moon_distance_km=...) for the moon of that instant."""
    return dict(_atmo.moon_position(str(date), float(latitude_deg), float(longitude_deg)))


def set_threads(threads: int) -> None:
    """At most `threads` worker threads for the module's work from now on, as `atmo --threads`;
    0 restores oneTBB's default (all cores)."""
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)):
        raise ValueError(f"threads must be an integer (got {threads!r})")
    _atmo.set_threads(int(threads))


def set_table_cache(folder, max_bytes: int = 1 << 30) -> None:
    """Keep the tables that source4d and elek models precompute in `folder` (a str or path), and
    read them back when a later Model has the same model, options, atmosphere and build
    (bit-identical to computing them); None keeps nothing, the module's default. The tables
    shipped with atmo (the default sky's, made when it was built) are read either way. `atmo.default_table_cache()` is
    the folder the atmo command uses. Files are written whole, checked when read, and the least
    recently used are removed past max_bytes (docs/python.md, "The table cache")."""
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, (int, np.integer)) or max_bytes <= 0:
        raise ValueError(f"max_bytes must be a positive integer (got {max_bytes!r})")
    _atmo.set_table_cache(None if folder is None else os.fspath(folder), int(max_bytes))


def table_cache():
    """The table cache's folder, or None when it keeps nothing."""
    return _atmo.table_cache()


def default_table_cache():
    """The folder the atmo command keeps tables in: $ATMO_TABLE_CACHE (None when "off"), else
    $XDG_CACHE_HOME/atmo/tables, else ~/.cache/atmo/tables."""
    return _atmo.default_table_cache()


def model_names() -> list:
    return list(_atmo.model_names())


def preset_names() -> list:
    return list(_atmo.preset_names())


def _memory_limit_bytes() -> float:
    """Half of the physical memory (the bound of Model.sample's arrays); 8 GiB where unknown."""
    try:
        return 0.5 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 8.0 * 2**30


def aerosol_types() -> list:
    """The OPAC aerosol types of the `aerosol=` keyword (docs/aerosols.md)."""
    return list(_atmo.aerosol_types())


def set_max_memory(size: Optional[str]) -> None:
    """The memory limit of `--max-memory` (docs/reliability.md, "Memory"): "4G", "512M", ...;
    None restores the default, half of this machine's memory. Models, renders and volumes whose
    estimate exceeds it raise ValueError before they allocate."""
    if size is not None and not isinstance(size, str):
        raise ValueError(f"size must be a string such as '4G' or None (got {size!r})")
    _atmo.set_max_memory(size or "")


def max_memory() -> int:
    """The memory limit in bytes (set_max_memory)."""
    return int(_atmo.max_memory())


def preset(name: str) -> dict:
    """A preset's parameters as the JSON of docs/parameters.md (edit it and pass it as config=)."""
    return json.loads(_atmo.preset_json(name))


def _parameters_json(preset: Optional[str], config, aerosol: Optional[str] = None) -> str:
    """The JSON of docs/parameters.md for a preset name, a config file or a dict (one of them)."""
    if preset is not None and config is not None:
        raise ValueError("give preset or config, not both")
    if isinstance(config, Mapping):
        return json.dumps(config)
    if config is not None:
        with open(os.fspath(config), encoding="utf-8") as f:
            return f.read()
    return _atmo.preset_json(preset or "us-standard")


def _planes(planes) -> list:
    """Planes as (tilt, azimuth) pairs or "sun", for the C++ side as (tilt, azimuth, tracks_sun)."""
    out = []
    for plane in planes:
        if isinstance(plane, str):
            if plane != "sun":
                raise ValueError(f"a plane is (tilt_deg, azimuth_deg) or 'sun' (got {plane!r})")
            out.append((0.0, 0.0, True))
        else:
            tilt, azimuth = plane
            out.append((float(tilt), float(azimuth), False))
    return out


def _options(options) -> dict:
    return {str(k): _option_text(str(k), v) for k, v in (options or {}).items()}


def irradiance(sun_elevation_deg: float, sun_azimuth_deg: float = 180.0, *, planes=((0.0, 180.0), "sun"),
               model: str = "source4d", preset: Optional[str] = None, config=None, options=None,
               altitude_m: float = 0.0, circumsolar_deg: float = 2.5, sun_scale: float = 1.0) -> dict:
    """The sun's and sky's light on planes, as `atmo irradiance` (include/atmo/irradiance.h): for
    each plane ((tilt_deg, azimuth_deg) or "sun"), direct, circumsolar, sky_diffuse,
    ground_reflected and global, each as _lux, _w_m2 (360-830 nm) and _spectral (W m^-2 nm^-1 per
    wavelength). Model source4d on us-standard unless given; sun_scale 1/d^2 for a dated sun."""
    return dict(_atmo.irradiance(model, _parameters_json(preset, config), _options(options), float(altitude_m),
                                 float(sun_elevation_deg), float(sun_azimuth_deg), _planes(planes),
                                 float(circumsolar_deg), float(sun_scale)))


def calibrate(direct_normal_lux: float, diffuse_horizontal_lux: float, sun_elevation_deg: float,
              sun_azimuth_deg: float = 180.0, *, model: str = "source4d", preset: Optional[str] = None, config=None,
              options=None, aerosol: str = "continental-average", altitude_m: float = 0.0,
              circumsolar_deg: float = 2.5, tolerance: float = 0.005, sun_scale: float = 1.0) -> dict:
    """The clear sky that reproduces a measured direct-normal (pyrheliometer) and diffuse-horizontal
    illuminance, as `atmo calibrate` (include/atmo/calibration.h): status ("clear", or why no clear
    sky gives them), aod_550, omega_550, the model's direct_normal_lux and diffuse_horizontal_lux,
    message, and parameters_json (a config for Model(config=json.loads(...)))."""
    return dict(_atmo.calibrate(model, _parameters_json(preset, config), _options(options), aerosol,
                                float(altitude_m), float(sun_elevation_deg), float(sun_azimuth_deg),
                                float(direct_normal_lux), float(diffuse_horizontal_lux), float(circumsolar_deg),
                                float(tolerance), float(sun_scale)))


def with_aerosol(aod_550: float, omega_550: Optional[float] = None, *, aerosol: str = "continental-average",
                 preset: Optional[str] = None, config=None) -> dict:
    """The parameters (a config dict, docs/parameters.md) with the aerosol `calibrate` and `annual`
    fit (include/atmo/calibration.h, WithAerosol): the type's column scaled to aod_550, its
    single-scattering albedo shifted to omega_550 at 550 nm (None: the type's own). With an hour's
    aod_550 and omega_550 from hours.csv, Model(config=...) is that hour's clear sky."""
    omega = float("nan") if omega_550 is None else float(omega_550)
    return json.loads(_atmo.with_aerosol(_parameters_json(preset, config), aerosol, float(aod_550), omega))


def read_epw(path: Union[str, os.PathLike]) -> dict:
    """An EnergyPlus weather file (include/atmo/weather.h): {"location": {...}, "hours": {field:
    NumPy array}}, with year, month, day, hour (1-24, the hour ending then), julian_day_utc (the
    middle of the hour), the irradiances (W m^-2), illuminances (lux), pressure_pa and albedo;
    missing values are NaN."""
    return dict(_atmo.read_epw(os.fspath(path)))


def annual(epw: Union[str, os.PathLike], out_dir: Union[str, os.PathLike], *, model: str = "source4d",
           preset: Optional[str] = None, config=None, options=None, aerosol: str = "continental-average",
           planes=(), subdivision: int = 1, patch_samples: int = 2, circumsolar_deg: float = 2.5,
           sun_in_matrix: bool = True, sky_maps: int = 0, per_wavelength: bool = False,
           hours: Optional[tuple] = None, shard: tuple = (0, 1)) -> dict:
    """One run (or shard) of `atmo annual` (include/atmo/annual.h): the selected hours of the
    weather file as calibrated skies, written as parts into out_dir, skipped when already there;
    out_dir/sky.mtx, hours.csv and irradiance.csv once every hour of the file is done. hours: (A, B),
    the file's hours A..B-1; shard: (I, N), the whole days whose number modulo N is I. Returns
    {selected, already_done, computed, file_done, models_built, merged}. Deterministic: any split
    into shards writes the bytes of one serial run. sky_maps: > 0, also each hour's sky as
    out_dir/maps/sky_HHHH.hdr (an angular fisheye this many pixels a side) and sky_HHHH.rad.
    per_wavelength: also out_dir/irradiance_spectral.csv, every plane's irradiance per channel in
    W m^-2 nm^-1."""
    first, end = (0, 2**63) if hours is None else (int(hours[0]), int(hours[1]))
    return dict(_atmo.annual(os.fspath(epw), os.fspath(out_dir), model, _parameters_json(preset, config),
                             _options(options), aerosol, _planes(planes), int(subdivision), int(patch_samples),
                             float(circumsolar_deg), bool(sun_in_matrix), int(sky_maps), bool(per_wavelength), first,
                             end, int(shard[0]), int(shard[1])))


def annual_on_dask(client, epw: Union[str, os.PathLike], out_dir: Union[str, os.PathLike], *,
                   shards: Optional[int] = None, retries: int = 3, progress=None,
                   threads_per_worker: Optional[int] = None, **kwargs) -> dict:
    """A year of `annual` on a Dask cluster (Debian's python3-distributed): `shards` tasks (default
    one per worker thread: each shard builds the table nodes its hours need, so fewer shards cost
    less), each atmo.annual(..., shard=(i, shards)) on some worker, retried up to
    `retries` times if its worker dies (a retried shard skips the hours its parts already hold),
    then the outputs merged here. progress(done, total), when given, is called as shards finish.
    Every worker must see out_dir (a shared file system) and import atmo. Returns {"shards": the
    reports, "merged": whether out_dir now holds the outputs}. threads_per_worker: atmo's threads in
    each worker (atmo.set_threads), so that workers sharing a machine do not oversubscribe it."""
    from distributed import as_completed  # noqa: PLC0415 (optional dependency)

    if threads_per_worker is not None:
        client.run(set_threads, int(threads_per_worker))
    if shards is None:
        shards = max(1, sum(client.nthreads().values()))
    futures = [client.submit(annual, os.fspath(epw), os.fspath(out_dir), shard=(i, shards), retries=retries,
                             pure=False, key=f"atmo-annual-{i}-of-{shards}", **kwargs)
               for i in range(shards)]
    reports = [None] * shards
    index = {f.key: i for i, f in enumerate(futures)}
    for done, future in enumerate(as_completed(futures), start=1):
        reports[index[future.key]] = future.result()
        if progress is not None:
            progress(done, shards)
    merge_keys = {k: kwargs[k] for k in ("model", "preset", "config", "options", "aerosol", "planes", "subdivision",
                                         "patch_samples", "circumsolar_deg", "sun_in_matrix", "sky_maps",
                                         "per_wavelength")
                  if k in kwargs}
    merged = _annual_merge(epw, out_dir, **merge_keys)
    return {"shards": reports, "merged": merged}


def _annual_merge(epw, out_dir, *, model: str = "source4d", preset: Optional[str] = None, config=None, options=None,
                  aerosol: str = "continental-average", planes=(), subdivision: int = 1, patch_samples: int = 2,
                  circumsolar_deg: float = 2.5, sun_in_matrix: bool = True, sky_maps: int = 0,
                  per_wavelength: bool = False) -> bool:
    return bool(_atmo.annual_merge(os.fspath(epw), os.fspath(out_dir), model, _parameters_json(preset, config),
                                   _options(options), aerosol, _planes(planes), int(subdivision), int(patch_samples),
                                   float(circumsolar_deg), bool(sun_in_matrix), int(sky_maps), bool(per_wavelength)))


def __dir__() -> list:
    """The public names only (PEP 562): not the modules this one imports."""
    return sorted(__all__ + ["__version__"])
