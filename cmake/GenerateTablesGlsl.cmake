# Generates atmo_tables.glsl, the one GLSL file an engine includes to sample the tables that
# `atmo precompute --model hillaire` exports (docs/tables.md). Script mode:
#
#   cmake -DGLSL_DIR=<src/atmo/shared> -DOUTPUT=<file.glsl> -P GenerateTablesGlsl.cmake
#
# It copies, verbatim from the shared GLSL/C++ sources (the text the CPU compiles as C++ and the GL
# backend embeds), only the functions the lookups need, each with the comment above it, in
# dependency order, after a prelude that gives the common subset its GLSL meaning (as
# src/atmo/gl/shader_sources.cc does) and a two-member atmosphere struct: the lookups read only
# the radii. Every copied name but the atmo* entry points is renamed atmo_NAME by a #define, and
# all the prelude's macros are #undef'd at the end, so that the file adds to an engine's shader
# only the atmo* functions, atmo_* helpers and the struct AtmoGeometry. A symbol that is not found
# stops the build: the file cannot drift from the sources.

# FILE:SYMBOL, in dependency order. A symbol is a function (copied to its closing "}" at the start
# of a line), a constant (to its ";") or a struct (to its closing "};" at the start of a line).
set(symbols
  definitions.glsl:kPi
  geometry.glsl:ClampToRange geometry.glsl:ClampCosine geometry.glsl:ClampDistance geometry.glsl:SafeSqrt
  geometry.glsl:DistanceToTopAtmosphereBoundary geometry.glsl:RayIntersectsGround
  transmittance.glsl:GetTextureCoordFromUnitRange transmittance.glsl:GetUnitRangeFromTextureCoord
  transmittance.glsl:GetTransmittanceTextureUvFromRMu transmittance.glsl:GetRMuFromTransmittanceTextureUv
  transmittance.glsl:GetTransmittanceToTopAtmosphereBoundary transmittance.glsl:GetTransmittance
  transmittance.glsl:GetTransmittanceToSun
  multiple_scattering.glsl:GetMultiScatteringUnitFromMuS multiple_scattering.glsl:GetMuSFromMultiScatteringUnit
  multiple_scattering.glsl:GetMultiScatteringTextureUvFromRMuS
  multiple_scattering.glsl:GetRMuSFromMultiScatteringTextureUv
  multiple_scattering.glsl:EncodeMultiScattering multiple_scattering.glsl:DecodeMultiScattering
  multiple_scattering.glsl:GetMultiScattering
  sky.glsl:GetHorizonNadirAngle sky.glsl:GetSkyViewTextureUvFromBeta sky.glsl:GetSkyViewTextureUvFromViewAngles
  sky.glsl:GetViewAnglesFromSkyViewTextureUv sky.glsl:GetSkyRadianceFromSkyView
  camera.glsl:GetAzimuthFromSun
  tables.glsl:atmoTransmittance tables.glsl:atmoTransmittanceAlong tables.glsl:atmoTransmittanceToSun
  tables.glsl:atmoMultipleScattering tables.glsl:atmoSkyView
  tables.glsl:GetAerialPerspectiveSliceFromDistance tables.glsl:GetAerialPerspectiveTextureUvwFromScreenDistance
  tables.glsl:GetScreenDistanceFromAerialPerspectiveTextureUvw tables.glsl:atmoAerialPerspective)

# EXTRA_SYMBOLS (optional, same form) adds functions after these: the web page's shader
# (web/CMakeLists.txt) takes the cameras and the sun's limb darkening too.
if(DEFINED EXTRA_SYMBOLS)
  string(REPLACE "," ";" extra "${EXTRA_SYMBOLS}")
  list(APPEND symbols ${extra})
endif()

set(renames "")
set(undefs "")
set(body "")
foreach(entry IN LISTS symbols)
  string(REPLACE ":" ";" parts "${entry}")
  list(GET parts 0 file)
  list(GET parts 1 name)
  file(READ "${GLSL_DIR}/${file}" text)
  set(text "\n${text}")
  string(REGEX MATCH "\n[A-Za-z0-9_]+ ${name}\\(" head "${text}")
  set(terminator "\n}\n")
  if(head STREQUAL "")
    string(REGEX MATCH "\nconst [A-Za-z0-9_]+ ${name} =" head "${text}")
    set(terminator ";\n")
  endif()
  if(head STREQUAL "")
    string(REGEX MATCH "\nstruct ${name} {" head "${text}")
    set(terminator "\n};\n")
  endif()
  if(head STREQUAL "")
    message(FATAL_ERROR "GenerateTablesGlsl: ${name} not found in ${GLSL_DIR}/${file}")
  endif()
  string(FIND "${text}" "${head}" start)
  # The comment lines right above the definition travel with it.
  string(SUBSTRING "${text}" 0 ${start} before)
  string(REGEX MATCH "(\n//[^\n]*)+$" comment "${before}")
  string(SUBSTRING "${text}" ${start} -1 rest)
  string(FIND "${rest}" "${terminator}" stop)
  if(terminator STREQUAL ";\n")
    # A constant ends at its ";", with the rest of that line (a trailing comment).
    string(FIND "${rest}" ";" semicolon)
    string(SUBSTRING "${rest}" ${semicolon} -1 after)
    string(FIND "${after}" "\n" line_end)
    if(semicolon EQUAL -1 OR line_end EQUAL -1)
      set(stop -1)
    else()
      math(EXPR stop "${semicolon} + ${line_end}")
    endif()
    set(terminator "\n")
  endif()
  if(stop EQUAL -1)
    message(FATAL_ERROR "GenerateTablesGlsl: the end of ${name} in ${file} not found")
  endif()
  string(LENGTH "${terminator}" terminator_length)
  math(EXPR stop "${stop} + ${terminator_length}")
  string(SUBSTRING "${rest}" 0 ${stop} definition)
  string(APPEND body "\n// -- ${name}, from src/atmo/shared/${file}${comment}${definition}")
  if(NOT name MATCHES "^atmo")
    string(APPEND renames "#define ${name} atmo_${name}\n")
    string(APPEND undefs "#undef ${name}\n")
  endif()
endforeach()

set(content "// atmo_tables.glsl: samples the tables exported by `atmo precompute --model hillaire`.
// Generated by cmake/GenerateTablesGlsl.cmake from atmo's shared sources (src/atmo/shared/*.glsl);
// do not edit. The format of the tables and every mapping are in the export's manifest
// (NAME.json) and in docs/tables.md.
//
// To use it: paste (or #include through GL_ARB_shading_language_include) this file after the
// `#version` line of any shader (tested with `#version 430 core`), upload the raw tables into
// GL_RGB32F textures with GL_LINEAR filtering and clamp to edge (the sky view: GL_REPEAT in s),
// then, lengths in km as in the manifest:
//   AtmoGeometry atmosphere = AtmoGeometry(bottom_radius_km, top_radius_km);
//   vec3 t  = atmoTransmittance(atmosphere, transmittance_table, r, mu);
//   vec3 ms = atmoMultipleScattering(atmosphere, multiple_scattering_table, r, mu_s);
//   vec3 l  = atmoSkyView(atmosphere, sky_view_table, r, view_direction, sun_direction) * solar_irradiance;
//   atmoAerialPerspective(aerial_radiance, aerial_transmittance, screen_uv, distance_km, max_distance_km,
//                         in_scattered, transmittance);
// Helpers (the mappings u(...) and their inverses) are named atmo_NAME, e.g.
// atmo_GetTransmittanceTextureUvFromRMu; nothing else is defined once the file ends.

#define Number float
#define IN(x) in x
#define OUT(x) out x
#define INOUT(x) inout x
#define TransmittanceTexture sampler2D
#define MultiScatteringTexture sampler2D
#define SkyViewTexture sampler2D
#define Texture3D sampler3D
#define AtmosphereParameters AtmoGeometry
${renames}
// The atmosphere as the lookups see it: the ground and top radii (km).
struct AtmosphereParameters {
  Number bottom_radius;
  Number top_radius;
};
${body}
#undef Number
#undef IN
#undef OUT
#undef INOUT
#undef TransmittanceTexture
#undef MultiScatteringTexture
#undef SkyViewTexture
#undef Texture3D
#undef AtmosphereParameters
${undefs}")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
  if(old STREQUAL content)
    return()
  endif()
endif()
file(WRITE "${OUTPUT}" "${content}")
