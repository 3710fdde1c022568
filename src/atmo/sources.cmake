# The atmo library's sources, one list for the native build (src/atmo/CMakeLists.txt) and the
# WebAssembly build (web/CMakeLists.txt). ATMO_IMAGE_FILE_SOURCES read and write image files through
# OpenEXR and libpng, which the WebAssembly build does without.
set(ATMO_CORE_SOURCES
  physics/parameters.cc
  physics/presets.cc
  physics/parameters_json.cc
  physics/spectrum.cc
  physics/colour.cc
  physics/shared_parameters.cc
  physics/sun_position.cc
  physics/standard_atmosphere.cc
  physics/gas_absorption.cc
  physics/gases.cc
  physics/aerosol.cc
  physics/night_sky.cc
  physics/moon.cc
  physics/stars.cc
  models/model.cc
  models/model_options.cc
  models/elek_model.cc
  models/hillaire_model.cc
  models/reference_model.cc
  models/simple_model.cc
  models/source4d_model.cc
  cpu/render.cc
  cpu/cubemap.cc
  cpu/engine_target.cc
  cpu/ibl.cc
  cpu/illuminance.cc
  cpu/irradiance.cc
  cpu/calibration.cc
  cpu/sky_patches.cc
  cpu/annual.cc
  cpu/progressive_render.cc
  cpu/sun_disc.cc
  cpu/path_tracer.cc
  cpu/aerial_perspective.cc
  cpu/elek_tables.cc
  cpu/hillaire_tables.cc
  cpu/source4d_tables.cc
  cpu/sky_view_lookup.cc
  io/elek_table_file.cc
  io/hillaire_table_file.cc
  io/table_files.cc
  io/display.cc
  io/files.cc
  io/night_vision.cc
  io/weather.cc
  io/annual_files.cc
  io/interrupt.cc
  io/ktx2.cc
  io/table_cache.cc
  metrics/metrics.cc
  timing.cc
  memory.cc
)
set(ATMO_IMAGE_FILE_SOURCES
  io/image_io.cc
)

# The CPU kernels written to vectorise: the table builders call exp and sqrt in loops, which needs
# them free of errno side effects and selects between computed values that may not trap; the frame
# renderer and the irradiance convolution (a float dot-product reduction) need the same. Their
# OpenMP simd pragmas take -fopenmp-simd (no OpenMP runtime).
set(ATMO_VECTORISED_SOURCES cpu/hillaire_tables.cc cpu/source4d_tables.cc cpu/render.cc cpu/ibl.cc)
set(ATMO_VECTORISED_OPTIONS -fno-math-errno -fno-trapping-math -fopenmp-simd)
