// Host/GPU structs of atmo, in the GLSL/C++ common subset (see glsl_cpp.h).
//
// Every length is in the unit of the parameters (metres on the CPU, km on the GPU); every
// coefficient is per that unit. Per-channel quantities are vec3: a model evaluates channels in
// batches of three wavelengths.

const Number kPi = 3.14159265358979323846;

// Phase-function identifiers (docs/design.md §2). All are normalised to 1 over the sphere and take
// nu = cos(angle between the view direction and the sun direction).
const int kPhaseIsotropic = 0;
const int kPhaseRayleigh = 1;           // 3/(16 pi) (1 + nu^2)
const int kPhaseModifiedRayleigh = 2;   // Atmosphere Plus: (1.4 + 0.5 nu^2) / (47/30 * 4 pi), see phase.glsl
const int kPhaseCornetteShanks = 3;     // 3/(8 pi) (1-g^2)(1+nu^2) / ((2+g^2)(1+g^2-2 g nu)^1.5)
const int kPhaseHenyeyGreenstein = 4;   // (1-g^2) / (4 pi (1+g^2-2 g nu)^1.5)
const int kPhaseTabulated = 5;          // the Mie medium's table, mie_phase_table (phase.glsl)

// Knots of a tabulated phase function: knot i sits at the scattering angle
// pi (i / (kPhaseTableSize - 1))^2, dense near 0 where aerosols' forward peaks are (0.011 degrees
// apart there, 2.8 degrees at 180); the table holds the natural logarithm of the phase function
// (per steradian, normalised to 1 over the sphere) at each, four knots to a vec4: 128 uniform
// components.
const int kPhaseTableSize = 128;
// The half-angle of a tabulated phase function's forward peak, which source4d's gathering grid
// cannot resolve (source4d.glsl, GetSource4dGatherMiePhase): 3 degrees.
const Number kPhasePeakAngle = 0.05235987755982989;

// One layer of a density profile, after Bruneton 2017: at altitude h the density is
// exp_term * exp(exp_scale * h) + linear_term * h + constant_term, clamped to [0, 1].
struct DensityProfileLayer {
  Number width;          // thickness of the layer (length); ignored for the top layer
  Number exp_term;       // unitless
  Number exp_scale;      // per length (negative: -1 / scale height)
  Number linear_term;    // per length
  Number constant_term;  // unitless
};

// Two layers: layers[0] below altitude layers[0].width, layers[1] above it.
struct DensityProfile {
  DensityProfileLayer layers[2];
};

// Knots of the tabulated densities (docs/parameters.md, "Tabulated profiles"): knot i sits at
// altitude density_table_top * (i / (kDensityTableSize - 1))^2, dense near the ground where the
// aerosol and the air change fastest (8 m apart at the ground, 1.6 km at the top of a 100 km
// atmosphere). 128 vec4 are 512 uniform components, half of the 1024 that GL 4.3 guarantees.
const int kDensityTableSize = 128;
// The natural logarithm that stands for a density of 0 in the table (exp(-80) = 1.8e-35).
const Number kDensityTableLogZero = -80.0;

struct AtmosphereParameters {
  Number bottom_radius;           // ground sphere radius (length)
  Number top_radius;              // top of the atmosphere (length)
  DensityProfile rayleigh_density;
  vec3 rayleigh_scattering;       // per length, at density 1
  vec3 rayleigh_extinction;       // per length, at density 1 (scattering + absorption)
  int rayleigh_phase;             // kPhaseRayleigh or kPhaseModifiedRayleigh
  DensityProfile mie_density;
  vec3 mie_scattering;            // per length, at density 1
  vec3 mie_extinction;            // per length, at density 1 (scattering + absorption)
  int mie_phase;                  // kPhaseCornetteShanks, kPhaseHenyeyGreenstein or kPhaseTabulated
  Number mie_g;                   // asymmetry, g > 0: forward peak towards the sun
  // kPhaseTabulated: ln of the Mie phase function at the knots above, knot i in component i % 4 of
  // element i / 4; unused (and not uploaded on the GPU) for the analytic phase functions.
  vec4 mie_phase_table[kPhaseTableSize / 4];
  // kPhaseTabulated: the table's value kPhasePeakAngle from forward, and the mass of its forward
  // peak above that value inside that angle (source4d's gathering, source4d.glsl); 0 otherwise.
  Number mie_phase_peak_cap;
  Number mie_phase_peak_mass;
  DensityProfile absorption_density;
  vec3 absorption_extinction;     // ozone absorption per length, at density 1
  // Water vapour absorption per length, at density 1: its density exists only in the table (w), so
  // it is 0 unless density_table_enabled.
  vec3 water_vapor_extinction;
  vec3 ground_albedo;             // Lambertian, unitless
  Number sun_angular_radius;      // radians
  vec3 wavelength;                // nm, per channel (the sun's limb darkening, sun.glsl)
  int sun_limb_darkening;         // 1: Neckel and Labs 1994's limb darkening; 0: a uniform disc
  vec3 sun_centre_radiance;       // sr^-1 per unit irradiance: GetSunDiscCentreRadiance per channel
  // 1: the four densities come from density_table and the three layer profiles above are unused
  // (at least one medium has a tabulated profile, or there is water vapour); 0: the layer profiles.
  int density_table_enabled;
  Number density_table_top;       // altitude of the last knot (length): the atmosphere's thickness
  // Knot i: the natural logarithms of the Rayleigh, Mie, ozone and water vapour densities (x, y, z, w),
  // each at least kDensityTableLogZero; interpolated linearly in the knot coordinate, so that each
  // density is exponential in altitude between knots.
  vec4 density_table[kDensityTableSize];
};

// Cameras (camera.glsl turns a pixel into a view direction).
const int kCameraPerspective = 0;  // pinhole: horizontal field of view, yaw (azimuth), pitch (elevation)
const int kCameraFisheye = 1;      // all-sky, equidistant: zenith at the centre, horizon on the circle, north up, east left
const int kCameraEquirect = 2;     // full-sphere lat-long: azimuth across (yaw at the centre), elevation +90..-90 down

struct CameraParameters {
  int kind;
  int width;               // pixels
  int height;              // pixels
  Number horizontal_fov;   // radians (perspective)
  Number yaw;              // radians, compass azimuth of the view centre
  Number pitch;            // radians, elevation of the view centre (perspective)
  // Derived by MakeCameraParameters, so that pixels need no trigonometry (perspective).
  vec3 forward;
  vec3 right;
  vec3 up;
  Number tan_half_fov;
};
