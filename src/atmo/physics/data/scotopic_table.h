// The CIE 1951 scotopic luminous efficiency function (read only through src/atmo/io/night_vision.cc).
#pragma once

namespace atmo::data {

// V'(lambda), CIE 1951 scotopic standard observer (as in ISO 23539:2005 / CIE S 010/E:2004), every
// 5 nm from 380 to 780 nm, peak 1 at 507 nm; 0 outside. Taken from the 1 nm table of the Colour &
// Vision Research Laboratory (UCL, file scvle_1) as reproduced in colour-science's
// colour/colorimetry/datasets/lefs.py (BSD-3-Clause), every fifth entry. Scotopic luminance is
// 1700 lm/W x integral of V'(lambda) L(lambda) d(lambda) (683 / V'(555 nm) = 683 / 0.402).
inline constexpr double kScotopicFirstNm = 380.0;
inline constexpr double kScotopicStepNm = 5.0;
inline constexpr int kScotopicCount = 81;
inline constexpr double kScotopicEfficiency[kScotopicCount] = {
    0.000589, 0.001108, 0.002209, 0.00453, 0.00929, 0.01852, 0.03484, 0.0604,
    0.0966, 0.1436, 0.1998, 0.2625, 0.3281, 0.3931, 0.455, 0.513,
    0.567, 0.62, 0.676, 0.734, 0.793, 0.851, 0.904, 0.949,
    0.982, 0.998, 0.997, 0.975, 0.935, 0.88, 0.811, 0.733,
    0.65, 0.564, 0.481, 0.402, 0.3288, 0.2639, 0.2076, 0.1602,
    0.1212, 0.0899, 0.0655, 0.0469, 0.03315, 0.02312, 0.01593, 0.01088,
    0.00737, 0.00497, 0.003335, 0.002235, 0.001497, 0.001005, 0.000677, 0.000459,
    0.0003129, 0.0002146, 0.000148, 0.0001026, 7.15e-05, 5.01e-05, 3.533e-05, 2.501e-05,
    1.78e-05, 1.273e-05, 9.14e-06, 6.6e-06, 4.78e-06, 3.482e-06, 2.546e-06, 1.87e-06,
    1.379e-06, 1.022e-06, 7.6e-07, 5.67e-07, 4.25e-07, 3.196e-07, 2.413e-07, 1.829e-07,
    1.39e-07,
};

}  // namespace atmo::data
