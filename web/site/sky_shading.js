// The sky's shading in GLSL ES 3.00, shared by the demo page (renderer.js) and the npm package's
// three.js adapter (three.js): the radiance along a view direction from a sky-view table
// (atmo.wasm's Model.skyView), plus the limb-darkened sun disc integrated over the pixel. Both
// include it after atmo_web.glsl (generated from atmo's shared sources: the mapping, the sun's
// limb darkening); the pixel's footprint comes from the caller as the view direction's change
// across one pixel in x and in y (exact camera rays on the page, dFdx/dFdy in three.js).
// docs/web.md.

export const kSkyShading = `
uniform sampler2D atmo_sky_view;     // RGBA32F (or 16F), linear sRGB cd/m^2; s repeats
uniform float atmo_r_km;             // the observer's radius
uniform float atmo_bottom_radius_km;
uniform float atmo_top_radius_km;
uniform float atmo_horizon_nadir_angle;  // GetHorizonNadirAngle at atmo_r_km (the table's, in double)
uniform vec3 atmo_sun_direction;     // local frame: x east, y north, z up
uniform vec3 atmo_sun_centre;        // the disc's centre radiance through the air, linear sRGB cd/m^2
uniform float atmo_sun_radius;       // angular radius, radians (0: no disc)

// The sky and the lit ground (no sun disc) along a unit direction of the local frame: atmoSkyView
// with the horizon's nadir angle computed once per table.
vec3 AtmoSky(vec3 view) {
  vec2 uv = atmo_GetSkyViewTextureUvFromBeta(textureSize(atmo_sky_view, 0), atmo_horizon_nadir_angle, view.z,
                                             atmo_GetAzimuthFromSun(view, atmo_sun_direction));
  return texture(atmo_sky_view, uv).rgb;
}

// Neckel and Labs's limb darkening at 610, 550 and 465 nm for R, G and B, relative to the centre.
vec3 AtmoLimbDarkening(float mu) {
  return vec3(atmo_GetSunLimbDarkening(610.0, mu) / atmo_GetSunLimbDarkening(610.0, 1.0),
              atmo_GetSunLimbDarkening(550.0, mu) / atmo_GetSunLimbDarkening(550.0, 1.0),
              atmo_GetSunLimbDarkening(465.0, mu) / atmo_GetSunLimbDarkening(465.0, 1.0));
}

// The sun disc's mean radiance over the pixel around the unit direction \`view\`, whose
// neighbours in x and y are view + dx and view + dy. Where the disc spans pixels it is sampled
// on a 16 x 16 grid of the pixel; a disc narrower than half a pixel puts its whole energy (its
// solid angle times its mean radiance) into the one pixel that holds its centre. Either way the
// disc's irradiance is right at any resolution.
vec3 AtmoSunDisc(vec3 view, vec3 dx, vec3 dy) {
  float pixel = max(length(dx), length(dy));
  vec3 offset = atmo_sun_direction - view;
  if (atmo_sun_radius <= 0.0 || length(offset) > atmo_sun_radius + 2.0 * pixel) {
    return vec3(0.0);
  }
  if (atmo_sun_radius < 0.5 * pixel) {
    // The pixel holds the centre when the sun's offset is within half a pixel along both axes.
    vec2 at = vec2(dot(offset, dx) / dot(dx, dx), dot(offset, dy) / dot(dy, dy));
    if (at.x < -0.5 || at.x >= 0.5 || at.y < -0.5 || at.y >= 0.5) {
      return vec3(0.0);
    }
    // The disc's mean darkening: the mean of f(mu) over its area, on 8 rings.
    vec3 mean = vec3(0.0);
    for (int k = 0; k < 8; ++k) {
      float rho = (float(k) + 0.5) / 8.0;
      mean += 2.0 * rho / 8.0 * AtmoLimbDarkening(sqrt(max(1.0 - rho * rho, 0.0)));
    }
    float sin_half = sin(0.5 * atmo_sun_radius);
    float disc = 4.0 * atmo_kPi * sin_half * sin_half;  // 2 pi (1 - cos r), without cos's error near 0
    return atmo_sun_centre * mean * disc / max(length(cross(dx, dy)), 1e-20);
  }
  vec3 sum = vec3(0.0);
  for (int j = 0; j < 16; ++j) {
    for (int i = 0; i < 16; ++i) {
      vec2 s = (vec2(i, j) + 0.5) / 16.0 - 0.5;
      vec3 v = normalize(view + s.x * dx + s.y * dy);
      float mu = atmo_GetSunDiscSurfaceCosine(dot(v, atmo_sun_direction), atmo_sun_radius);
      if (mu >= 0.0) {
        sum += AtmoLimbDarkening(mu);
      }
    }
  }
  return atmo_sun_centre * sum / 256.0;
}
`;

// The uniforms' values for a table (Model.skyView's result) and a sun (degrees of elevation and
// compass azimuth), as plain numbers and arrays, for WebGL or three.js.
export function skyUniformValues(table, sunElevationDeg, sunAzimuthDeg, sunDisc = true) {
  const e = (sunElevationDeg * Math.PI) / 180;
  const a = (sunAzimuthDeg * Math.PI) / 180;
  return {
    atmo_r_km: table.rKm,
    atmo_bottom_radius_km: table.bottomRadiusKm,
    atmo_top_radius_km: table.topRadiusKm,
    atmo_horizon_nadir_angle: table.horizonNadirAngle,
    atmo_sun_direction: [Math.cos(e) * Math.sin(a), Math.cos(e) * Math.cos(a), Math.sin(e)],
    atmo_sun_centre: [table.sunDisc[0], table.sunDisc[1], table.sunDisc[2]],
    atmo_sun_radius: sunDisc ? table.sunAngularRadius : 0,
  };
}

// The exposure multiplier of an EV100 (atmo's ExposureFromEv100): L_max = 1.2 x 2^EV100 maps to 1.
export function exposureFromEv100(ev100) {
  return 1 / (1.2 * 2 ** ev100);
}
