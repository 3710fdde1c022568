// Ray/sphere geometry for a spherical planet, in the (r, mu) parameters of Bruneton 2017:
// r is the distance from the planet centre, mu the cosine of the ray's zenith angle.
//
// A ray x + t v with |x| = r, dot(x, v) = r mu meets the sphere of radius R where
// t^2 + 2 r mu t + (r^2 - R^2) = 0, i.e. t = -r mu +- sqrt(D) with D = r^2 mu^2 - (r^2 - R^2).
// Near the horizon both r^2 and R^2 are ~4e13 m^2, so D is formed as (R - r)(R + r) + r^2 mu^2,
// and the root that suffers cancellation is obtained from the product of the roots
// (r^2 - R^2) instead of by subtraction. This keeps grazing rays accurate, also in float.

// clamp(x, lo, hi) that maps NaN to lo: every comparison with NaN is false, so NaN takes the
// first branch. GLSL's clamp and glm::clamp (like std::clamp) let NaN through, and a NaN texture
// coordinate or table column then became an index far outside the table (the audit's crash for
// radii of 1e154 m). Every clamp of the shared code that feeds a lookup goes through this one.
Number ClampToRange(Number x, Number lo, Number hi) {
  return !(x > lo) ? lo : (x < hi ? x : hi);
}

Number ClampCosine(Number mu) {
  return ClampToRange(mu, -1.0, 1.0);
}

// max(d, 0) with NaN -> 0.
Number ClampDistance(Number d) {
  return d > 0.0 ? d : 0.0;
}

// sqrt(max(a, 0)) with NaN -> 0.
Number SafeSqrt(Number a) {
  return sqrt(a > 0.0 ? a : 0.0);
}

// Distance from a point at radius r <= top_radius, along mu, to the top atmosphere boundary.
Number DistanceToTopAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu) {
  Number c = (atmosphere.top_radius - r) * (atmosphere.top_radius + r);  // R^2 - r^2 >= 0
  Number root = SafeSqrt(c + r * r * mu * mu);
  // Far root -r mu + sqrt(D); for mu > 0 it equals c / (r mu + sqrt(D)) without cancellation.
  return ClampDistance(mu > 0.0 ? c / (r * mu + root) : -r * mu + root);
}

// True when the ray (r, mu) meets the ground.
bool RayIntersectsGround(IN(AtmosphereParameters) atmosphere, Number r, Number mu) {
  return mu < 0.0 &&
      (atmosphere.bottom_radius - r) * (atmosphere.bottom_radius + r) + r * r * mu * mu >= 0.0;
}

// Distance from a point at radius r >= bottom_radius, along mu, to the ground. Valid where
// RayIntersectsGround(r, mu): the near root -r mu - sqrt(D), written as (r^2 - R^2) / (-r mu + sqrt(D)).
Number DistanceToBottomAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu) {
  Number c = (r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius);  // r^2 - R^2 >= 0
  Number denominator = -r * mu + SafeSqrt(r * r * mu * mu - c);
  return denominator > 0.0 ? ClampDistance(c / denominator) : 0.0;
}

// Distance to the ground if the ray meets it, else to the top of the atmosphere.
Number DistanceToNearestAtmosphereBoundary(IN(AtmosphereParameters) atmosphere, Number r, Number mu,
    bool ray_r_mu_intersects_ground) {
  return ray_r_mu_intersects_ground ? DistanceToBottomAtmosphereBoundary(atmosphere, r, mu)
                                    : DistanceToTopAtmosphereBoundary(atmosphere, r, mu);
}

// Cosine of the zenith angle of the geometric horizon seen from radius r (the horizon dips
// below mu = 0 as the observer rises): mu_horizon = -sqrt(1 - (R/r)^2).
Number CosineOfHorizonZenith(IN(AtmosphereParameters) atmosphere, Number r) {
  Number rho = SafeSqrt((r - atmosphere.bottom_radius) * (r + atmosphere.bottom_radius));
  return -rho / r;
}

// For an observer outside the atmosphere (r > top_radius): distance along mu to where the ray
// enters the atmosphere, or -1 when it misses it.
Number DistanceToAtmosphereEntry(IN(AtmosphereParameters) atmosphere, Number r, Number mu) {
  Number c = (r - atmosphere.top_radius) * (r + atmosphere.top_radius);  // r^2 - R^2 > 0
  Number discriminant = r * r * mu * mu - c;
  if (mu >= 0.0 || discriminant < 0.0) {
    return -1.0;
  }
  return c / (-r * mu + sqrt(discriminant));
}
