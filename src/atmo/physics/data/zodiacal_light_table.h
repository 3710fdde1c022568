// The zodiacal light's brightness over the sky (a published table atmo ships; read only through
// src/atmo/physics/night_sky.cc).
#pragma once

namespace atmo::data {

// Leinert et al. 1998, "The 1997 reference of diffuse night sky brightness", A&AS 127, 1-99,
// Table 17: the zodiacal light at 500 nm seen from the Earth (1 au, in the ecliptic), in units of
// 1e-8 W m^-2 sr^-1 um^-1, by helio-ecliptic longitude lambda - lambda_sun (rows) and absolute
// ecliptic latitude beta (columns), both in degrees. The cells too close to the sun for a
// measurement (elongation under ~15 degrees near the ecliptic) hold 0 here. Transcribed from the
// machine-readable copy in EXOSIMS (github.com/dsavransky/EXOSIMS,
// EXOSIMS/ZodiacalLight/Leinert98_table17.txt, BSD-3-Clause), checked cell by cell against a
// second copy (github.com/GerritRo/nyx, nyx/data/leinert1998_zodiacal_light.dat) except for its
// beta = 90 column, which that copy gives in other units.
inline constexpr int kZodiacalLongitudeCount = 19;
inline constexpr int kZodiacalLatitudeCount = 11;
inline constexpr double kZodiacalLongitudeDeg[kZodiacalLongitudeCount] = {
    0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 60, 75, 90, 105, 120, 135, 150, 165, 180};
inline constexpr double kZodiacalLatitudeDeg[kZodiacalLatitudeCount] = {0, 5, 10, 15, 20, 25, 30, 45, 60, 75, 90};
inline constexpr double kZodiacalLight500[kZodiacalLongitudeCount][kZodiacalLatitudeCount] = {
    {0, 0, 0, 3140, 1610, 985, 640, 275, 150, 100, 77},
    {0, 0, 0, 2940, 1540, 945, 625, 271, 150, 100, 77},
    {0, 0, 4740, 2470, 1370, 865, 590, 264, 148, 100, 77},
    {11500, 6780, 3440, 1860, 1110, 755, 525, 251, 146, 100, 77},
    {6400, 4480, 2410, 1410, 910, 635, 454, 237, 141, 99, 77},
    {3840, 2830, 1730, 1100, 749, 545, 410, 223, 136, 97, 77},
    {2480, 1870, 1220, 845, 615, 467, 365, 207, 131, 95, 77},
    {1650, 1270, 910, 680, 510, 397, 320, 193, 125, 93, 77},
    {1180, 940, 700, 530, 416, 338, 282, 179, 120, 92, 77},
    {910, 730, 555, 442, 356, 292, 250, 166, 116, 90, 77},
    {505, 442, 352, 292, 243, 209, 183, 134, 104, 86, 77},
    {338, 317, 269, 227, 196, 172, 151, 116, 93, 82, 77},
    {259, 251, 225, 193, 166, 147, 132, 104, 86, 79, 77},
    {212, 210, 197, 170, 150, 133, 119, 96, 82, 77, 77},
    {188, 186, 177, 154, 138, 125, 113, 90, 77, 74, 77},
    {179, 178, 166, 147, 134, 122, 110, 90, 77, 73, 77},
    {179, 178, 165, 148, 137, 127, 116, 96, 79, 72, 77},
    {196, 192, 179, 165, 151, 141, 131, 104, 82, 72, 77},
    {230, 212, 195, 178, 163, 148, 134, 105, 83, 72, 77},
};

}  // namespace atmo::data
