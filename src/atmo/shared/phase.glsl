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

// The knot coordinate of a scattering angle's cosine in the phase table (0 forward,
// kPhaseTableSize - 1 backward): knot i is at the angle pi (i / (kPhaseTableSize - 1))^2.
Number GetPhaseTableCoord(Number nu) {
  return sqrt(acos(ClampToRange(nu, -1.0, 1.0)) / kPi) * Number(kPhaseTableSize - 1);
}

// The solid angle per unit of the knot coordinate u: 2 pi sin(theta) dtheta/du, with
// theta = pi (u / (kPhaseTableSize - 1))^2 (the measure that normalises and samples the table).
Number GetPhaseTableSolidAnglePerKnot(Number u) {
  Number m = Number(kPhaseTableSize - 1);
  return 2.0 * kPi * sin(kPi * (u / m) * (u / m)) * (2.0 * kPi * u / (m * m));
}

Number GetPhaseTableKnot(IN(AtmosphereParameters) atmosphere, int i) {
  return atmosphere.mie_phase_table[i / 4][i % 4];
}

// The tabulated Mie phase function: its logarithm linear in the knot coordinate between knots.
Number TabulatedMiePhaseFunction(IN(AtmosphereParameters) atmosphere, Number nu) {
  Number u = GetPhaseTableCoord(nu);
  Number lower = min(floor(u), Number(kPhaseTableSize - 2));
  int i = int(lower);
  return exp(mix(GetPhaseTableKnot(atmosphere, i), GetPhaseTableKnot(atmosphere, i + 1), u - lower));
}

// The phase functions of an atmosphere's two scattering media.
Number GetRayleighPhase(IN(AtmosphereParameters) atmosphere, Number nu) {
  return EvaluatePhaseFunction(atmosphere.rayleigh_phase, 0.0, nu);
}

Number GetMiePhase(IN(AtmosphereParameters) atmosphere, Number nu) {
  if (atmosphere.mie_phase == kPhaseTabulated) return TabulatedMiePhaseFunction(atmosphere, nu);
  return EvaluatePhaseFunction(atmosphere.mie_phase, atmosphere.mie_g, nu);
}

// A medium's phase function by its identifier, the tabulated one from the atmosphere's table.
Number GetMediumPhase(IN(AtmosphereParameters) atmosphere, int kind, Number g, Number nu) {
  if (kind == kPhaseTabulated) return TabulatedMiePhaseFunction(atmosphere, nu);
  return EvaluatePhaseFunction(kind, g, nu);
}
