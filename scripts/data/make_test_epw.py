#!/usr/bin/env python3
"""Writes tests/data/greensboro_tmy3.epw: NREL's TMY3 year for Greensboro, NC (WMO 723170) as an
EnergyPlus weather file, for the tests and the annual benchmark of docs/daylighting.md.

Source: the TMY3 file 723170TYA.CSV (Wilcox and Marion 2008, "Users Manual for TMY3 Data Sets",
NREL/TP-581-43156), produced by the National Renewable Energy Laboratory for the US Department of
Energy and in the public domain; read from the copy that pvlib-python keeps as
pvlib/data/723170TYA.CSV (BSD-3-Clause project).  TMY3's illuminances are not measured: NREL
modelled them from the irradiances with Perez et al. 1990's luminous efficacy (the manual, section
1.4); the irradiances are measured or modelled per hour (their source flags are kept in the EPW's
data source field as TMY3 gives them, first letter only).

The fields are mapped as EnergyPlus's weather converter maps TMY3 (EnergyPlus Auxiliary Programs,
"Weather Converter Program"): time 01:00..24:00 is the hour ending then, in local standard time;
pressure mbar -> Pa, visibility m -> km, precipitable water cm -> mm, and the illuminances x 100
(TMY3 keeps them in hundreds of lux despite its "(lx)" headers: 826 at a direct normal irradiance of
820 W m^-2); the zenith luminance, whose unit the file does not make clear, and what TMY3 lacks are
EPW's missing codes.

Usage: make_test_epw.py 723170TYA.CSV > tests/data/greensboro_tmy3.epw
"""
import csv
import sys


def main(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    station = rows[0]
    wmo, name, state, tz, lat, lon, elev = station[0], station[1], station[2], float(station[3]), float(station[4]), float(station[5]), float(station[6])
    head = rows[1]
    col = {k: i for i, k in enumerate(head)}
    out = sys.stdout
    out.write(f"LOCATION,{name.title()},{state},USA,TMY3,{wmo},{lat:.2f},{lon:.2f},{tz:.1f},{elev:.1f}\r\n")
    out.write("DESIGN CONDITIONS,0\r\nTYPICAL/EXTREME PERIODS,0\r\nGROUND TEMPERATURES,0\r\n")
    out.write("HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\r\n")
    out.write("COMMENTS 1,NREL TMY3 723170TYA (public domain); converted by atmo scripts/data/make_test_epw.py\r\n")
    out.write("COMMENTS 2,TMY3 illuminances are modelled from irradiance (Perez et al. 1990)\r\n")
    out.write("DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31\r\n")

    def get(r, key, scale=1.0, missing=None):
        v = r[col[key]]
        try:
            return float(v) * scale
        except ValueError:
            return missing

    for r in rows[2:]:
        month, day, year = (int(x) for x in r[col["Date (MM/DD/YYYY)"]].split("/"))
        hour = int(r[col["Time (HH:MM)"]].split(":")[0])
        flags = "".join((r[col[k + " source"]] or "?")[:1] + "9" for k in ["GHI", "DNI", "DHI"])
        fields = [year, month, day, hour, 0, flags,
                  get(r, "Dry-bulb (C)"), get(r, "Dew-point (C)"), int(get(r, "RHum (%)")),
                  int(get(r, "Pressure (mbar)") * 100), int(get(r, "ETR (W/m^2)")), int(get(r, "ETRN (W/m^2)")), 9999,
                  int(get(r, "GHI (W/m^2)")), int(get(r, "DNI (W/m^2)")), int(get(r, "DHI (W/m^2)")),
                  int(get(r, "GH illum (lx)") * 100), int(get(r, "DN illum (lx)") * 100),
                  int(get(r, "DH illum (lx)") * 100), 9999, int(get(r, "Wdir (degrees)")), get(r, "Wspd (m/s)"),
                  int(get(r, "TotCld (tenths)")), int(get(r, "OpqCld (tenths)")), get(r, "Hvis (m)", 0.001),
                  int(get(r, "CeilHgt (m)")), 9, 999999999, int(round(get(r, "Pwat (cm)", 10.0))),
                  f"{get(r, 'AOD (unitless)'):.4f}", 999, 99, f"{get(r, 'Alb (unitless)'):.3f}",
                  get(r, "Lprecip depth (mm)"), get(r, "Lprecip quantity (hr)")]
        out.write(",".join(str(x) for x in fields) + "\r\n")


if __name__ == "__main__":
    main(sys.argv[1])
