# Writes a TMY3 year (NREL's typical meteorological year, the CSV format pvlib ships in its
# wheel as pvlib/data/723170TYA.CSV: Greensboro, North Carolina) as an EnergyPlus weather file,
# keeping what daylight needs: the LOCATION line, and per hour the date, the irradiances and
# the illuminances (the other fields written as the EPW's missing-value codes).
# NREL's TMY3 files give illuminance in units of 100 lx (their header says lx; the values are
# about 1.08 per W/m² of global irradiance, where daylight's efficacy is about 110 lm/W): they
# are multiplied by 100 here.
#   python3 scripts/tmy3_to_epw.py 723170TYA.CSV scenes/office/greensboro.epw
import csv
import sys


def main(src, dst):
    with open(src, newline="") as f:
        rows = list(csv.reader(f))
    station, name, state, tz, lat, lon, elev = rows[0][:7]
    out = [
        f"LOCATION,{name.strip()},{state},USA,TMY3,{station},{float(lat):.3f},{float(lon):.3f},"
        f"{float(tz):.1f},{float(elev):.1f}",
        "DESIGN CONDITIONS,0",
        "TYPICAL/EXTREME PERIODS,0",
        "GROUND TEMPERATURES,0",
        "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
        "COMMENTS 1,NREL TMY3 (public domain) via scripts/tmy3_to_epw.py; daylight fields only",
        "COMMENTS 2,illuminance = TMY3 value x 100",
        "DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31",
    ]
    for r in rows[2:]:
        month, day, year = r[0].split("/")
        hour = int(r[1].split(":")[0])
        ghi, dni, dhi = r[4], r[7], r[10]
        gil, dnil, dhil = (int(float(r[i]) * 100) for i in (13, 16, 19))
        fields = [year, str(int(month)), str(int(day)), str(hour), "60", "_",
                  "99.9", "99.9", "999", "999999", "9999", "9999", "9999",
                  ghi, dni, dhi, str(gil), str(dnil), str(dhil), "9999"]
        out.append(",".join(fields))
    with open(dst, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
