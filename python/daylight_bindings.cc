// The daylighting functions of the Python module (docs/python.md, docs/daylighting.md): irradiance
// on planes, the calibration of a clear sky, EPW files and annual runs (one shard each, for Dask).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "atmo/annual.h"
#include "atmo/calibration.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/irradiance.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "atmo/weather.h"

namespace py = pybind11;

namespace atmo::python {

namespace {

// (tilt, azimuth, tracks_sun) triples from the Python layer.
std::vector<Plane> Planes(const std::vector<std::tuple<double, double, bool>>& planes) {
  std::vector<Plane> out;
  for (const auto& [tilt, azimuth, tracks] : planes) out.push_back(tracks ? Plane::FacingSun() : Plane{tilt, azimuth});
  return out;
}

py::array_t<double> Array(const std::vector<double>& v) { return py::array_t<double>(v.size(), v.data()); }

py::dict Components(const IrradianceComponents& e, const SpectralConversion& convert) {
  py::dict d;
  const std::vector<double> global = e.Global();
  const std::pair<const char*, const std::vector<double>*> parts[] = {
      {"direct", &e.direct}, {"circumsolar", &e.circumsolar}, {"sky_diffuse", &e.sky_diffuse},
      {"ground_reflected", &e.ground_reflected}, {"global", &global}};
  for (const auto& [name, values] : parts) {
    d[(std::string(name) + "_lux").c_str()] = convert.Luminance(*values);
    d[(std::string(name) + "_w_m2").c_str()] = convert.Radiance(*values);
    std::vector<double> spectral(values->size());
    for (std::size_t c = 0; c < spectral.size(); ++c) spectral[c] = convert.SpectralRadiance(c, (*values)[c]);
    d[(std::string(name) + "_spectral").c_str()] = Array(spectral);
  }
  return d;
}

AnnualSettings Settings(const std::string& model, const ModelOptions& options, const std::string& aerosol_type,
                        const std::vector<std::tuple<double, double, bool>>& planes, int subdivision,
                        int patch_samples, double circumsolar_deg, bool sun_in_matrix, int sky_map_size = 0,
                        bool per_wavelength = false) {
  AnnualSettings s;
  s.model = model;
  s.options = options;
  s.aerosol_type = aerosol_type;
  s.planes = Planes(planes);
  s.sky_subdivision = subdivision;
  s.patch_samples = patch_samples;
  s.circumsolar_half_angle_deg = circumsolar_deg;
  s.sun_in_matrix = sun_in_matrix;
  s.sky_map_size = sky_map_size;
  s.per_wavelength = per_wavelength;
  return s;
}

}  // namespace

void AddDaylightBindings(py::module_& m) {
  m.def(
      "irradiance",
      [](const std::string& model_name, const std::string& parameters_json, const ModelOptions& options,
         double altitude_m, double sun_elevation_deg, double sun_azimuth_deg,
         const std::vector<std::tuple<double, double, bool>>& planes, double circumsolar_deg, double sun_scale) {
        AtmosphereParameters p = FromJson(parameters_json);
        p.solar_irradiance.assign(p.channel_count(), 1.0);
        IrradianceResult r;
        {
          py::gil_scoped_release release;
          const std::unique_ptr<Model> model = CreateModel(model_name, p, options);
          IrradianceSettings s;
          s.circumsolar_half_angle_deg = circumsolar_deg;
          s.sun_scale = sun_scale;
          r = ComputeIrradiance(*model->View(altitude_m, SunDirection(sun_elevation_deg, sun_azimuth_deg)), p,
                                Planes(planes), s);
        }
        const SpectralConversion convert(p.wavelengths_nm);
        py::dict d;
        d["wavelengths_nm"] = Array(p.wavelengths_nm);
        d["direct_normal_lux"] = convert.Luminance(r.direct_normal);
        py::list list;
        for (const IrradianceComponents& e : r.planes) list.append(Components(e, convert));
        d["planes"] = list;
        return d;
      },
      py::arg("model"), py::arg("parameters_json"), py::arg("options"), py::arg("altitude_m"),
      py::arg("sun_elevation_deg"), py::arg("sun_azimuth_deg"), py::arg("planes"), py::arg("circumsolar_deg"),
      py::arg("sun_scale"));

  m.def(
      "calibrate",
      [](const std::string& model_name, const std::string& parameters_json, const ModelOptions& options,
         const std::string& aerosol_type, double altitude_m, double sun_elevation_deg, double sun_azimuth_deg,
         double direct_normal_lux, double diffuse_horizontal_lux, double circumsolar_deg, double tolerance,
         double sun_scale) {
        const AtmosphereParameters base = FromJson(parameters_json);
        CalibrationSettings s;
        s.model = model_name;
        s.options = options;
        s.aerosol_type = aerosol_type;
        s.circumsolar_half_angle_deg = circumsolar_deg;
        s.tolerance = tolerance;
        s.sun_scale = sun_scale;
        CalibrationResult r;
        {
          py::gil_scoped_release release;
          r = CalibrateClearSky(base, altitude_m, SunDirection(sun_elevation_deg, sun_azimuth_deg),
                                {direct_normal_lux, diffuse_horizontal_lux}, s);
        }
        py::dict d;
        d["status"] = std::string(ToString(r.status));
        d["aod_550"] = r.aod_550;
        d["omega_550"] = r.single_scattering_albedo_550;
        d["direct_normal_lux"] = r.direct_normal_lux;
        d["diffuse_horizontal_lux"] = r.diffuse_horizontal_lux;
        d["models_built"] = r.model_builds;
        d["message"] = r.message;
        d["parameters_json"] = ToJson(r.parameters);
        return d;
      },
      py::arg("model"), py::arg("parameters_json"), py::arg("options"), py::arg("aerosol_type"), py::arg("altitude_m"),
      py::arg("sun_elevation_deg"), py::arg("sun_azimuth_deg"), py::arg("direct_normal_lux"),
      py::arg("diffuse_horizontal_lux"), py::arg("circumsolar_deg"), py::arg("tolerance"), py::arg("sun_scale"));

  m.def(
      "with_aerosol",
      [](const std::string& parameters_json, const std::string& type, double aod_550, double omega_550) {
        return ToJson(WithAerosol(FromJson(parameters_json), type, aod_550, omega_550));
      },
      py::arg("parameters_json"), py::arg("aerosol_type"), py::arg("aod_550"), py::arg("omega_550"));

  m.def(
      "read_epw",
      [](const std::string& path) {
        const WeatherFile w = ReadEpw(path);
        py::dict location;
        location["city"] = w.location.city;
        location["region"] = w.location.region;
        location["country"] = w.location.country;
        location["source"] = w.location.source;
        location["wmo"] = w.location.wmo;
        location["latitude_deg"] = w.location.latitude_deg;
        location["longitude_deg"] = w.location.longitude_deg;
        location["time_zone_h"] = w.location.time_zone_h;
        location["elevation_m"] = w.location.elevation_m;
        std::vector<double> fields[13];
        for (const WeatherHour& h : w.hours) {
          const double values[13] = {double(h.year), double(h.month), double(h.day), double(h.hour),
                                     MidHourJulianDayUtc(w.location, h), h.global_horizontal_w_m2,
                                     h.direct_normal_w_m2, h.diffuse_horizontal_w_m2, h.global_horizontal_lux,
                                     h.direct_normal_lux, h.diffuse_horizontal_lux, h.pressure_pa, h.albedo};
          for (int k = 0; k < 13; ++k) fields[k].push_back(values[k]);
        }
        static const char* names[13] = {"year", "month", "day", "hour", "julian_day_utc", "global_horizontal_w_m2",
                                         "direct_normal_w_m2", "diffuse_horizontal_w_m2", "global_horizontal_lux",
                                         "direct_normal_lux", "diffuse_horizontal_lux", "pressure_pa", "albedo"};
        py::dict hours;
        for (int k = 0; k < 13; ++k) hours[names[k]] = Array(fields[k]);
        py::dict d;
        d["location"] = location;
        d["hours"] = hours;
        return d;
      },
      py::arg("path"));

  m.def(
      "annual",
      [](const std::string& epw, const std::string& out_dir, const std::string& model, const std::string& parameters_json,
         const ModelOptions& options, const std::string& aerosol_type,
         const std::vector<std::tuple<double, double, bool>>& planes, int subdivision, int patch_samples,
         double circumsolar_deg, bool sun_in_matrix, int sky_map_size, bool per_wavelength, std::size_t first_hour,
         std::size_t end_hour, int shard, int shards) {
        AnnualRunReport report;
        {
          py::gil_scoped_release release;
          AnnualSkies skies(FromJson(parameters_json), ReadEpw(epw),
                            Settings(model, options, aerosol_type, planes, subdivision, patch_samples,
                                     circumsolar_deg, sun_in_matrix, sky_map_size, per_wavelength));
          report = RunAnnual(skies, AnnualRun{out_dir, first_hour, end_hour, shard, shards});
        }
        py::dict d;
        d["selected"] = report.selected;
        d["already_done"] = report.already_done;
        d["computed"] = report.computed;
        d["file_done"] = report.file_done;
        d["models_built"] = report.models_built;
        d["merged"] = report.merged;
        return d;
      },
      py::arg("epw"), py::arg("out_dir"), py::arg("model"), py::arg("parameters_json"), py::arg("options"),
      py::arg("aerosol_type"), py::arg("planes"), py::arg("subdivision"), py::arg("patch_samples"),
      py::arg("circumsolar_deg"), py::arg("sun_in_matrix"), py::arg("sky_map_size"), py::arg("per_wavelength"),
      py::arg("first_hour"), py::arg("end_hour"), py::arg("shard"), py::arg("shards"));

  m.def(
      "annual_merge",
      [](const std::string& epw, const std::string& out_dir, const std::string& model, const std::string& parameters_json,
         const ModelOptions& options, const std::string& aerosol_type,
         const std::vector<std::tuple<double, double, bool>>& planes, int subdivision, int patch_samples,
         double circumsolar_deg, bool sun_in_matrix, int sky_map_size, bool per_wavelength) {
        py::gil_scoped_release release;
        const AnnualSkies skies(FromJson(parameters_json), ReadEpw(epw),
                                Settings(model, options, aerosol_type, planes, subdivision, patch_samples,
                                         circumsolar_deg, sun_in_matrix, sky_map_size, per_wavelength));
        return MergeAnnual(skies, out_dir);
      },
      py::arg("epw"), py::arg("out_dir"), py::arg("model"), py::arg("parameters_json"), py::arg("options"),
      py::arg("aerosol_type"), py::arg("planes"), py::arg("subdivision"), py::arg("patch_samples"),
      py::arg("circumsolar_deg"), py::arg("sun_in_matrix"), py::arg("sky_map_size"), py::arg("per_wavelength"));
}

}  // namespace atmo::python
