// Phase functions, normalised to 1 over the sphere (the Atmosphere Plus seed writes them x 4 pi).
// nu is the cosine of the angle between the view direction and the sun direction, so for g > 0
// the forward peak is seen when looking towards the sun (docs/design.md §2).

Number IsotropicPhaseFunction() {
  return 1.0 / (4.0 * kPi);
}

Number RayleighPhaseFunction(Number nu) {
  return 3.0 / (16.0 * kPi) * (1.0 + nu * nu);
}

// Atmosphere Plus's "modified Rayleigh" has the shape 1.4 + 0.5 nu^2. The seed's 0.8 (1.4 + 0.5 nu^2)
// (over 4 pi) integrates over the sphere to 0.8 * 47/30 = 1.2533, not 1, and every phase function
// here is normalised (docs/design.md §2), so the shape is kept and divided by its integral, 47/30 * 4 pi.
Number ModifiedRayleighPhaseFunction(Number nu) {
  return (1.4 + 0.5 * nu * nu) / (47.0 / 30.0 * 4.0 * kPi);
}

Number CornetteShanksPhaseFunction(Number g, Number nu) {
  Number k = 3.0 / (8.0 * kPi) * (1.0 - g * g) / (2.0 + g * g);
  Number denominator = 1.0 + g * g - 2.0 * g * nu;
  return k * (1.0 + nu * nu) / (denominator * sqrt(denominator));
}

Number HenyeyGreensteinPhaseFunction(Number g, Number nu) {
  Number denominator = 1.0 + g * g - 2.0 * g * nu;
  return (1.0 - g * g) / (4.0 * kPi * denominator * sqrt(denominator));
}

Number EvaluatePhaseFunction(int kind, Number g, Number nu) {
  if (kind == kPhaseRayleigh) return RayleighPhaseFunction(nu);
  if (kind == kPhaseModifiedRayleigh) return ModifiedRayleighPhaseFunction(nu);
  if (kind == kPhaseCornetteShanks) return CornetteShanksPhaseFunction(g, nu);
  if (kind == kPhaseHenyeyGreenstein) return HenyeyGreensteinPhaseFunction(g, nu);
  return IsotropicPhaseFunction();
}

// The phase functions of an atmosphere's two scattering media.
Number GetRayleighPhase(IN(AtmosphereParameters) atmosphere, Number nu) {
  return EvaluatePhaseFunction(atmosphere.rayleigh_phase, 0.0, nu);
}

Number GetMiePhase(IN(AtmosphereParameters) atmosphere, Number nu) {
  return EvaluatePhaseFunction(atmosphere.mie_phase, atmosphere.mie_g, nu);
}
