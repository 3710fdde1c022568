// Standard tropospheric aerosol types of OPAC, for `--aerosol TYPE`: spectral extinction (relative
// to 550 nm), single-scattering albedo and asymmetry parameter g, at 350-900 nm, for relative
// humidity 70 %, with the vertical profile OPAC gives each type, and OPAC's free-tropospheric and
// stratospheric background layers. Nothing is fetched at run time.
//
// SOURCE
//   Hess, M., P. Koepke and I. Schult (1998): Optical Properties of Aerosols and Clouds: The
//   Software Package OPAC. Bull. Amer. Meteor. Soc. 79(5), 831-844,
//   doi:10.1175/1520-0477(1998)079<0831:OPOAAC>2.0.CO;2. The numbers below are NOT read from the
//   paper's tables (its text was not available to us); they come from the OPAC software package's
//   own data and configuration files, as redistributed in:
//     * github.com/mukeshraeee/SBDART_OPAC_Automated,
//       commit 5e464b83270a1ff66214571a569c4e6f6ff0184a, AutomateOpac/opac/ : component files
//       inso00, soot00, minm00, miam00, micm00, mitr00, waso70, ssam70, sscm70, suso70 (and
//       waso50, suso00 for the background layers), the configuration opac.cfg ("OPAC 3.13":
//       number densities and height profiles of the 10 aerosol types), extback.dat
//       (free-troposphere and stratosphere extinction), and the program opac.f (v3.16), whose
//       mixing and optical-depth rules are followed here.
//       Licence: the repository has no licence file; its README credits OPAC to Michael Hess.
//     * github.com/aubema/illumina, commit cadadca86beaed20d8569147a968be27089ec27d,
//       Aerosol_optics/OPAC_data/ holds byte-identical copies of the same component files (checked
//       by checksum), and Aerosol_optics/combination_types the same number densities.
//       Licence: GPL-3.0 (LICENSE-GPL at the repository root).
//   The OPAC files themselves carry no licence statement; OPAC was distributed freely by its
//   authors (Meteorological Institute, University of Munich). Only numerical data is used here.
//
// HOW THE NUMBERS WERE MADE (our computation from the files above; nothing is hand-tuned)
//   OPAC stores, per component and RH, extinction/scattering coefficients (1/km) for 1 particle
//   per cm^3, SSA and g at 61 wavelengths. A type is an external mixture with number densities N_i:
//     ext = sum N_i ext_i,  SSA = sum N_i sca_i / ext,  g = sum N_i sca_i g_i / sum N_i sca_i
//   (opac.f, subroutine optpar). Hygroscopic components (WASO, SSAM, SSCM, SUSO) are taken at
//   RH 70 %; INSO, SOOT and the mineral components have dry data only. Wavelengths are OPAC's own
//   grid points (no interpolation). Particles are spheres (OPAC 3.1 Mie data; OPAC 4's spheroidal
//   dust is not used, so desert g and the dust phase function are those of spheres).
//   Check: the same code run at RH 80 % gives, for continental polluted at 550 nm, ext 0.1746 /km,
//   SSA 0.8925, g 0.6977, optical depth 0.327, identical to an OPAC 3.1 output file published by
//   IPSL/ETHER (forge.ipsl.jussieu.fr/ether/export/1/trunk/hftp/iasi/aerosol/opac_calc/copo).
//   At RH 80 % the total optical depths at 550 nm come out as: continental clean 0.064, average
//   0.151, polluted 0.327, urban 0.643, desert 0.286, maritime clean 0.096, polluted 0.117,
//   tropical 0.056, arctic 0.063, antarctic 0.072 (for comparison with values quoted
//   elsewhere at RH 80 %).
//
// VERTICAL PROFILE (opac.cfg, applied as in opac.f)
//   Mixing (boundary) layer from 0 m to layer_top_m: ext(h) = extinction_550_per_m * exp(-h / Z),
//   Z = scale_height_m, zero above layer_top_m. OPAC writes Z = 99 km (arctic) to mean "about
//   constant with height"; that value is kept as is.
//   Free troposphere from the type's layer_top_m up to 12 km: ext(h) = 2.96e-6 /m * exp(-h / 8 km)
//   (note: referred to h = 0, not to the layer bottom), kFreeTroposphere below.
//   Stratosphere 12-35 km: constant 2.14e-7 /m, kStratosphere below.
//   typical_aod_550 is the whole column (mixing layer + free troposphere + stratosphere) at 550 nm
//   for the default profile and RH 70 %, i.e. OPAC's "op.depth"; boundary_layer_aod_550 is the
//   mixing layer's share alone. Both are computed, OPAC itself states no "typical" value.
//
// UNITS: wavelength in nm; extinction_relative_550 dimensionless (1 at 550 nm); SSA and g
// dimensionless; heights in m; extinction in 1/m. RH = 70 % for every type.
// OPAC's component files also hold full phase functions (167 angles) if a two-term
// Henyey-Greenstein fit is wanted later; only g is carried here.
#pragma once

namespace atmo::data {

struct AerosolSpectralPoint {
  double wavelength_nm;
  double extinction_relative_550;
  double single_scattering_albedo;
  double asymmetry_g;
};

struct AerosolType {
  const char* name;         // kebab-case, for --aerosol
  const char* description;  // one line
  const AerosolSpectralPoint* spectrum;
  int spectrum_count;
  double scale_height_m;          // mixing-layer exponential scale height Z
  double layer_top_m;             // top of the mixing layer (profile is zero above it)
  double typical_aod_550;         // whole column, default OPAC profile, RH 70 %
  double extinction_550_per_m;    // mixing-layer extinction at the ground, OPAC number densities
  double boundary_layer_aod_550;  // mixing layer only
};

// A background layer: ext(h) = extinction_550_per_m * exp(-h / scale_height_m) between bottom_m
// and top_m (scale_height_m == 0: constant extinction_550_per_m in the layer).
struct AerosolBackgroundLayer {
  const char* name;
  const char* description;
  const AerosolSpectralPoint* spectrum;
  int spectrum_count;
  double bottom_m;  // free troposphere: starts at the type's layer_top_m; 2000 is the default
  double top_m;
  double scale_height_m;
  double extinction_550_per_m;
  double aod_550;  // column of this layer for the default bottom
};

inline constexpr int kAerosolSpectrumCount = 11;

// continental-clean: INSO 0.15, WASO 2600 particles/cm^3.
// Angstrom exponent 400-800 nm = 1.35.
inline constexpr AerosolSpectralPoint kContinentalClean[] = {
    {350.0, 1.688, 0.9744, 0.7225},
    {400.0, 1.471, 0.9727, 0.7161},
    {450.0, 1.288, 0.9712, 0.7097},
    {500.0, 1.132, 0.9708, 0.7024},
    {550.0, 1.0, 0.9664, 0.6962},
    {600.0, 0.8886, 0.9648, 0.6891},
    {650.0, 0.794, 0.9601, 0.6822},
    {700.0, 0.7134, 0.9584, 0.6754},
    {750.0, 0.6438, 0.9520, 0.6697},
    {800.0, 0.5763, 0.9448, 0.6654},
    {900.0, 0.4812, 0.9309, 0.6541},
};

// continental-average: INSO 0.4, WASO 7000, SOOT 8300 particles/cm^3.
// Angstrom exponent 400-800 nm = 1.36.
inline constexpr AerosolSpectralPoint kContinentalAverage[] = {
    {350.0, 1.699, 0.9209, 0.7151},
    {400.0, 1.477, 0.9189, 0.7089},
    {450.0, 1.291, 0.9170, 0.7029},
    {500.0, 1.133, 0.9159, 0.6960},
    {550.0, 1.0, 0.9116, 0.6902},
    {600.0, 0.888, 0.9092, 0.6834},
    {650.0, 0.7936, 0.9035, 0.6769},
    {700.0, 0.7129, 0.9011, 0.6704},
    {750.0, 0.6437, 0.8937, 0.6649},
    {800.0, 0.5771, 0.8849, 0.6608},
    {900.0, 0.4829, 0.8685, 0.6499},
};

// continental-polluted: INSO 0.6, WASO 15700, SOOT 34300 particles/cm^3.
// Angstrom exponent 400-800 nm = 1.39.
inline constexpr AerosolSpectralPoint kContinentalPolluted[] = {
    {350.0, 1.719, 0.8838, 0.7079},
    {400.0, 1.49, 0.8816, 0.7018},
    {450.0, 1.299, 0.8794, 0.6959},
    {500.0, 1.137, 0.8779, 0.6890},
    {550.0, 1.0, 0.8735, 0.6832},
    {600.0, 0.8856, 0.8707, 0.6765},
    {650.0, 0.7897, 0.8642, 0.6698},
    {700.0, 0.7073, 0.8612, 0.6632},
    {750.0, 0.6371, 0.8530, 0.6576},
    {800.0, 0.57, 0.8427, 0.6531},
    {900.0, 0.4747, 0.8240, 0.6415},
};

// urban: INSO 1.5, WASO 28000, SOOT 130000 particles/cm^3.
// Angstrom exponent 400-800 nm = 1.37.
inline constexpr AerosolSpectralPoint kUrban[] = {
    {350.0, 1.725, 0.8039, 0.6951},
    {400.0, 1.492, 0.8005, 0.6896},
    {450.0, 1.299, 0.7970, 0.6844},
    {500.0, 1.137, 0.7939, 0.6784},
    {550.0, 1.0, 0.7890, 0.6734},
    {600.0, 0.8866, 0.7849, 0.6675},
    {650.0, 0.7925, 0.7770, 0.6617},
    {700.0, 0.7112, 0.7728, 0.6560},
    {750.0, 0.6427, 0.7634, 0.6511},
    {800.0, 0.5781, 0.7514, 0.6474},
    {900.0, 0.4858, 0.7305, 0.6375},
};

// desert: WASO 2000, MINM 269.5, MIAM 30.5, MICM 0.142 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.16.
inline constexpr AerosolSpectralPoint kDesert[] = {
    {350.0, 1.084, 0.7595, 0.7864},
    {400.0, 1.058, 0.7913, 0.7705},
    {450.0, 1.036, 0.8382, 0.7509},
    {500.0, 1.016, 0.8518, 0.7420},
    {550.0, 1.0, 0.8852, 0.7276},
    {600.0, 0.9857, 0.9039, 0.7185},
    {650.0, 0.9751, 0.9069, 0.7131},
    {700.0, 0.9654, 0.9176, 0.7073},
    {750.0, 0.9562, 0.9209, 0.7040},
    {800.0, 0.9488, 0.9234, 0.7008},
    {900.0, 0.9372, 0.9280, 0.6963},
};

// maritime-clean: WASO 1500, SSAM 20, SSCM 0.0032 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.11.
inline constexpr AerosolSpectralPoint kMaritimeClean[] = {
    {350.0, 1.057, 0.9960, 0.7694},
    {400.0, 1.037, 0.9963, 0.7675},
    {450.0, 1.021, 0.9967, 0.7664},
    {500.0, 1.01, 0.9972, 0.7643},
    {550.0, 1.0, 0.9970, 0.7649},
    {600.0, 0.9911, 0.9973, 0.7670},
    {650.0, 0.9842, 0.9971, 0.7675},
    {700.0, 0.9773, 0.9974, 0.7680},
    {750.0, 0.9699, 0.9971, 0.7704},
    {800.0, 0.9625, 0.9968, 0.7722},
    {900.0, 0.9467, 0.9964, 0.7741},
};

// maritime-polluted: WASO 3800, SOOT 5180, SSAM 20, SSCM 0.0032 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.39.
inline constexpr AerosolSpectralPoint kMaritimePolluted[] = {
    {350.0, 1.208, 0.9610, 0.7506},
    {400.0, 1.14, 0.9636, 0.7492},
    {450.0, 1.084, 0.9662, 0.7485},
    {500.0, 1.039, 0.9690, 0.7469},
    {550.0, 1.0, 0.9705, 0.7478},
    {600.0, 0.9671, 0.9725, 0.7499},
    {650.0, 0.9399, 0.9734, 0.7507},
    {700.0, 0.9157, 0.9751, 0.7516},
    {750.0, 0.894, 0.9754, 0.7543},
    {800.0, 0.8729, 0.9756, 0.7568},
    {900.0, 0.8389, 0.9759, 0.7597},
};

// maritime-tropical: WASO 590, SSAM 10, SSCM 0.0013 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.06.
inline constexpr AerosolSpectralPoint kMaritimeTropical[] = {
    {350.0, 1.034, 0.9967, 0.7721},
    {400.0, 1.021, 0.9970, 0.7702},
    {450.0, 1.011, 0.9973, 0.7690},
    {500.0, 1.005, 0.9977, 0.7668},
    {550.0, 1.0, 0.9976, 0.7673},
    {600.0, 0.9949, 0.9978, 0.7695},
    {650.0, 0.9913, 0.9977, 0.7699},
    {700.0, 0.9872, 0.9979, 0.7704},
    {750.0, 0.982, 0.9976, 0.7727},
    {800.0, 0.9769, 0.9974, 0.7744},
    {900.0, 0.9641, 0.9971, 0.7761},
};

// arctic: INSO 0.01, WASO 1300, SOOT 5300, SSAM 1.9 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.91.
inline constexpr AerosolSpectralPoint kArctic[] = {
    {350.0, 1.497, 0.8570, 0.7155},
    {400.0, 1.336, 0.8595, 0.7131},
    {450.0, 1.204, 0.8623, 0.7114},
    {500.0, 1.094, 0.8658, 0.7091},
    {550.0, 1.0, 0.8681, 0.7089},
    {600.0, 0.9222, 0.8711, 0.7091},
    {650.0, 0.8578, 0.8717, 0.7090},
    {700.0, 0.8018, 0.8749, 0.7092},
    {750.0, 0.754, 0.8748, 0.7111},
    {800.0, 0.7088, 0.8742, 0.7137},
    {900.0, 0.6421, 0.8733, 0.7166},
};

// antarctic: SSAM 0.047, MITR 0.0053, SUSO 42.9 particles/cm^3.
// Angstrom exponent 400-800 nm = 0.69.
inline constexpr AerosolSpectralPoint kAntarctic[] = {
    {350.0, 1.222, 0.9991, 0.7743},
    {400.0, 1.174, 0.9991, 0.7782},
    {450.0, 1.118, 0.9993, 0.7801},
    {500.0, 1.061, 0.9993, 0.7790},
    {550.0, 1.0, 0.9995, 0.7780},
    {600.0, 0.9411, 0.9995, 0.7760},
    {650.0, 0.8845, 0.9995, 0.7740},
    {700.0, 0.8306, 0.9996, 0.7711},
    {750.0, 0.7785, 0.9996, 0.7682},
    {800.0, 0.7286, 0.9995, 0.7643},
    {900.0, 0.6405, 0.9995, 0.7575},
};

// Free troposphere. Extinction relative to 550 nm: extback.dat column "free tropos." (source
// data). SSA and g: extback.dat gives extinction only, so these are DERIVED by us: the mixture
// WASO(50 %) 438 + SOOT 300 + INSO 0.0012 particles/cm^3, found by a least-squares fit of the
// component extinctions to that column, reproduces it within 0.4 % at every wavelength here
// (within 4 % from 0.25 to 40 um); SSA and g are that mixture's. Angstrom 400-800 nm = 1.48.
inline constexpr AerosolSpectralPoint kFreeTroposphereBackground[] = {
    {350.0, 1.76, 0.9403, 0.6972},
    {400.0, 1.517, 0.9392, 0.6904},
    {450.0, 1.314, 0.9383, 0.6827},
    {500.0, 1.145, 0.9373, 0.6749},
    {550.0, 1.0, 0.9327, 0.6682},
    {600.0, 0.8784, 0.9310, 0.6595},
    {650.0, 0.777, 0.9251, 0.6528},
    {700.0, 0.6892, 0.9232, 0.6441},
    {750.0, 0.6182, 0.9147, 0.6373},
    {800.0, 0.5439, 0.9044, 0.6316},
    {900.0, 0.4459, 0.8848, 0.6171},
};

// Stratosphere (sulphuric-acid background). Extinction relative to 550 nm: extback.dat column
// "stratosphere" (source data). SSA and g: DERIVED by us from OPAC's sulfate component SUSO at
// 0 % RH (suso00): 3.0 particles/cm^3 of it reproduces the column within 0.3 % here (within 1 %
// from 0.25 to 40 um), so the layer is taken to be that component. Angstrom 400-800 nm = 1.02.
inline constexpr AerosolSpectralPoint kStratosphereBackground[] = {
    {350.0, 1.416, 1.0000, 0.7180},
    {400.0, 1.299, 1.0000, 0.7230},
    {450.0, 1.187, 1.0000, 0.7240},
    {500.0, 1.089, 1.0000, 0.7210},
    {550.0, 1.0, 1.0000, 0.7170},
    {600.0, 0.9112, 1.0000, 0.7120},
    {650.0, 0.8364, 1.0000, 0.7070},
    {700.0, 0.7617, 1.0000, 0.7020},
    {750.0, 0.6963, 1.0000, 0.6960},
    {800.0, 0.6402, 1.0000, 0.6910},
    {900.0, 0.5374, 1.0000, 0.6790},
};

inline constexpr AerosolType kAerosolTypes[] = {
    {"continental-clean", "remote land: water-soluble particles, a trace of soil dust, no soot",
     kContinentalClean, kAerosolSpectrumCount, 8000.0, 2000.0, 0.0567, 2.185e-05, 0.0387},
    {"continental-average", "ordinary inland air with some anthropogenic soot",
     kContinentalAverage, kAerosolSpectrumCount, 8000.0, 2000.0, 0.1303, 6.339e-05, 0.1122},
    {"continental-polluted", "industrialised region: more water-soluble particles and soot",
     kContinentalPolluted, kAerosolSpectrumCount, 8000.0, 2000.0, 0.2806, 0.0001483, 0.2625},
    {"urban", "city haze with a heavy soot load; the most absorbing type",
     kUrban, kAerosolSpectrumCount, 8000.0, 2000.0, 0.5602, 0.0003063, 0.5421},
    {"desert", "mineral dust over arid land, three spherical dust modes",
     kDesert, kAerosolSpectrumCount, 2000.0, 6000.0, 0.2794, 0.0001413, 0.2686},
    {"maritime-clean", "open ocean: sea salt plus a little water-soluble aerosol",
     kMaritimeClean, kAerosolSpectrumCount, 1000.0, 2000.0, 0.0831, 7.517e-05, 0.0650},
    {"maritime-polluted", "coastal or shipping-lane air: sea salt with soot and sulphate",
     kMaritimePolluted, kAerosolSpectrumCount, 1000.0, 2000.0, 0.1013, 9.624e-05, 0.0832},
    {"maritime-tropical", "clean tropical ocean, less sea salt and sulphate",
     kMaritimeTropical, kAerosolSpectrumCount, 1000.0, 2000.0, 0.0494, 3.626e-05, 0.0314},
    {"arctic", "arctic haze: water-soluble particles with soot, a little sea salt",
     kArctic, kAerosolSpectrumCount, 99000.0, 2000.0, 0.0562, 1.927e-05, 0.0381},
    {"antarctic", "antarctic background, mostly sulphate droplets",
     kAntarctic, kAerosolSpectrumCount, 8000.0, 10000.0, 0.0603, 9.441e-06, 0.0539},
};
inline constexpr int kAerosolTypeCount = sizeof(kAerosolTypes) / sizeof(kAerosolTypes[0]);

inline constexpr AerosolBackgroundLayer kFreeTroposphere = {
    "free-troposphere", "aged background aerosol above the mixing layer",
    kFreeTroposphereBackground, kAerosolSpectrumCount, 2000.0, 12000.0, 8000.0, 2.96e-06, 0.0132};

inline constexpr AerosolBackgroundLayer kStratosphere = {
    "stratosphere", "sulphuric-acid droplet background layer", kStratosphereBackground,
    kAerosolSpectrumCount, 12000.0, 35000.0, 0.0, 2.14e-07, 0.0049};

}  // namespace atmo::data

