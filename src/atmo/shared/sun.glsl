// The sun disc: its limb darkening and the radiance that makes its irradiance exact.
//
// Limb darkening. The Sun's continuum intensity falls from the disc centre to the limb. Neckel
// and Labs (1994, "Limb darkening of the solar disk", Solar Physics 153, 91-114) fitted it at 30
// continuum wavelengths (303-1099 nm) by fifth-degree polynomials in mu, the cosine of the angle
// between the line of sight and the normal of the solar surface:
//   f(mu) = I(mu) / I(1) = sum_{k=0..5} a_k(lambda) mu^k,
// and represented the coefficients as polynomials in 1/lambda (lambda in micrometres) over three
// ranges, 300-372.98, 385-422.57 and 422.57-1100 nm (the fits as given by Neckel 2005, "Analytical
// reference functions F(lambda) for the Sun's limb darkening and its absolute continuum
// intensities (300 to 1100 nm)", Solar Physics 229, 13-33):
//   a_0 = a_00 + a_01 / lambda,
//   a_1 = a_10 + a_11 / lambda + a_15 / lambda^5,
//   a_k = a_k0 + a_k5 / lambda^5   (k = 2..5),
// with a_10 = 1 - (a_00 + a_20 + ... + a_50), a_11 = -a_01 and a_15 = -(a_25 + ... + a_55), so
// that f(1) = 1 at every wavelength. Between the first two ranges (the Balmer jump, 372.98-385 nm)
// and outside 300-1100 nm the nearest end of a range is used.
//
// Where the line of sight meets the Sun. A sphere seen under angular radius alpha from a distance
// D has radius R = D sin(alpha). The ray at angle theta from the centre passes the centre at
// b = D sin(theta) and meets the surface where the normal makes mu = sqrt(1 - (b / R)^2) with it:
//   mu = sqrt(1 - sin^2(theta) / sin^2(alpha)),   exact for any alpha.
//
// Normalisation. The disc's irradiance (its radiance integrated over its solid angle, as
// everywhere in atmo: E = int L dOmega) must stay E = 1 at the top of the atmosphere, the unit
// of every model. With L(theta) = L_c f(mu(theta)) and dOmega = 2 pi dt, t = cos(theta) in
// [cos(alpha), 1], mu^2 = (t^2 - cos^2 alpha) / sin^2 alpha gives mu dmu = t dt / sin^2 alpha:
//   E = L_c int f dOmega = L_c 2 pi sin^2(alpha) int_0^1 f(mu) mu / t(mu) dmu,
//   t(mu) = sqrt(cos^2 alpha + mu^2 sin^2 alpha).
// Writing Omega_sun = 2 pi (1 - cos alpha) and sin^2 alpha / (1 - cos alpha) = 1 + cos alpha,
//   E = L_c Omega_sun m,   m = (1 + cos alpha) int_0^1 f(mu) mu / t(mu) dmu,
// where m is the mean of f over the disc's solid angle (1 for a uniform disc). As alpha -> 0,
// t -> 1 and m -> 2 int_0^1 f(mu) mu dmu = 2 sum_k a_k / (k + 2), the classical flux ratio
// F / (pi I(1)) (0.806 at 560 nm); for the Sun's alpha = 0.0047 the two differ by 2e-6, for a
// 20 degree disc by ~0.2 %. Hence
//   L_c = E / (Omega_sun m).
// The integrand is a degree-6 polynomial times 1 / t, which is 1 + O(sin^2 alpha mu^2) and
// analytic on [0, 1]: Gauss-Legendre with 8 nodes (exact to degree 15) leaves < 1e-10.

// The coefficients a_0 .. a_5 of Neckel and Labs' f(mu) at a wavelength in nm.
void GetSunLimbDarkeningCoefficients(Number wavelength_nm, OUT(vec3) a012, OUT(vec3) a345) {
  Number lambda_nm = ClampToRange(wavelength_nm, 300.0, 1100.0);
  if (lambda_nm >= 372.98 && lambda_nm < 385.0) {
    lambda_nm = lambda_nm - 372.98 < 385.0 - lambda_nm ? 372.98 : 385.0;
  }
  Number inverse = 1000.0 / lambda_nm;  // 1 / lambda, lambda in micrometres
  Number inverse5 = inverse * inverse * inverse * inverse * inverse;
  if (lambda_nm < 372.98) {
    a012 = vec3(0.35601 - 0.085217 * inverse, 1.11529 + 0.085217 * inverse - 0.001871 * inverse5,
        -0.67237 + 0.003589 * inverse5);
    a345 = vec3(0.18696 - 0.002415 * inverse5, 0.00038 + 0.000897 * inverse5, 0.01373 - 0.000200 * inverse5);
  } else if (lambda_nm < 422.57) {
    a012 = vec3(0.09900 + 0.010643 * inverse, 1.96884 - 0.010643 * inverse - 0.009166 * inverse5,
        -2.80511 + 0.024873 * inverse5);
    a345 = vec3(3.32780 - 0.029317 * inverse5, -2.17878 + 0.018273 * inverse5, 0.58825 - 0.004663 * inverse5);
  } else {
    a012 = vec3(0.75267 - 0.265577 * inverse, 0.93874 + 0.265577 * inverse - 0.004095 * inverse5,
        -1.89287 + 0.012582 * inverse5);
    a345 = vec3(2.42234 - 0.017117 * inverse5, -1.71150 + 0.011977 * inverse5, 0.49062 - 0.003347 * inverse5);
  }
}

Number EvaluateSunLimbDarkening(IN(vec3) a012, IN(vec3) a345, Number mu) {
  return a012.x + mu * (a012.y + mu * (a012.z + mu * (a345.x + mu * (a345.y + mu * a345.z))));
}

// f(mu) = I(mu) / I(1) at a wavelength in nm (mu in [0, 1]).
Number GetSunLimbDarkening(Number wavelength_nm, Number mu) {
  vec3 a012;
  vec3 a345;
  GetSunLimbDarkeningCoefficients(wavelength_nm, a012, a345);
  return EvaluateSunLimbDarkening(a012, a345, ClampToRange(mu, 0.0, 1.0));
}

// Node i (0..3) and weight of the 8-point Gauss-Legendre rule on [-1, 1]: +-x_i with weight w_i.
Number GetGaussLegendre8Node(int i) {
  return i == 0 ? 0.1834346424956498 : i == 1 ? 0.5255324099163290 : i == 2 ? 0.7966664774136267 :
      0.9602898564975363;
}

Number GetGaussLegendre8Weight(int i) {
  return i == 0 ? 0.3626837833783620 : i == 1 ? 0.3137066458778873 : i == 2 ? 0.2223810344533745 :
      0.1012285362903763;
}

// m, the mean of f over the disc's solid angle (see the top): (1 + cos alpha) int_0^1 f mu / t dmu.
// `limb_darkening` false: 1 (a uniform disc).
Number GetSunDiscMeanLimbDarkening(Number wavelength_nm, Number sun_angular_radius, bool limb_darkening) {
  if (!limb_darkening) {
    return 1.0;
  }
  vec3 a012;
  vec3 a345;
  GetSunLimbDarkeningCoefficients(wavelength_nm, a012, a345);
  Number cos_alpha = cos(sun_angular_radius);
  Number sin_alpha = sin(sun_angular_radius);
  Number sum = 0.0;
  for (int i = 0; i < 8; ++i) {
    Number x = (i < 4 ? -1.0 : 1.0) * GetGaussLegendre8Node(i < 4 ? i : i - 4);
    Number mu = 0.5 * (x + 1.0);
    Number t = sqrt(cos_alpha * cos_alpha + mu * mu * sin_alpha * sin_alpha);
    sum += 0.5 * GetGaussLegendre8Weight(i < 4 ? i : i - 4) * EvaluateSunLimbDarkening(a012, a345, mu) * mu / t;
  }
  return (1.0 + cos_alpha) * sum;
}

// L_c = 1 / (Omega_sun m): the radiance at the disc centre for a unit irradiance, with
// Omega_sun = 2 pi (1 - cos alpha) written 4 pi sin^2(alpha / 2), without the cancellation that
// costs float 0.2 % for the Sun's alpha.
Number GetSunDiscCentreRadiance(Number wavelength_nm, Number sun_angular_radius, bool limb_darkening) {
  Number sin_half_alpha = sin(0.5 * sun_angular_radius);
  return 1.0 / (4.0 * kPi * sin_half_alpha * sin_half_alpha *
      GetSunDiscMeanLimbDarkening(wavelength_nm, sun_angular_radius, limb_darkening));
}

// mu on the solar surface (see the top) for a view at nu = cos(theta) from the sun's centre;
// negative off the disc (nu < cos alpha). sin^2 theta = (1 - nu)(1 + nu) and
// sin^2 alpha = (1 - cos alpha)(1 + cos alpha), with 1 - cos alpha = 2 sin^2(alpha / 2).
// The test is on 1 - nu against 1 - cos alpha = 2 sin^2(alpha / 2), not on nu against cos alpha:
// in float, a GPU's cos near 0 may be off by more than 1 - cos alpha's 1e-5 ulps (SwiftShader's
// widened the disc by two pixels of a 20-degree view), while sin of a small angle is accurate.
Number GetSunDiscSurfaceCosine(Number nu, Number sun_angular_radius) {
  Number sin_half_alpha = sin(0.5 * sun_angular_radius);
  Number one_minus_cos_alpha = 2.0 * sin_half_alpha * sin_half_alpha;
  if (1.0 - nu > one_minus_cos_alpha) {
    return -1.0;
  }
  Number sin2_alpha = one_minus_cos_alpha * (2.0 - one_minus_cos_alpha);
  Number sin2_theta = max(1.0 - nu, 0.0) * (1.0 + nu);
  return sqrt(max(1.0 - sin2_theta / sin2_alpha, 0.0));
}

// The disc's radiance per unit irradiance at the top of the atmosphere, before the atmosphere
// attenuates it, per channel: L_c f(mu) with the atmosphere's per-channel L_c and wavelengths;
// 0 off the disc (nu < cos alpha).
vec3 GetSunDiscUnattenuatedRadiance(IN(AtmosphereParameters) atmosphere, Number nu) {
  Number mu = GetSunDiscSurfaceCosine(nu, atmosphere.sun_angular_radius);
  if (mu < 0.0) {
    return vec3(0.0);
  }
  if (atmosphere.sun_limb_darkening == 0) {
    return atmosphere.sun_centre_radiance;
  }
  return atmosphere.sun_centre_radiance * vec3(GetSunLimbDarkening(atmosphere.wavelength.x, mu),
      GetSunLimbDarkening(atmosphere.wavelength.y, mu), GetSunLimbDarkening(atmosphere.wavelength.z, mu));
}
