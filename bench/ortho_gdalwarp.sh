#!/usr/bin/env bash
# bench/ortho_gdalwarp.sh: tp-ortho against GDAL's gdalwarp -rpc (issue 53): speed and pixel agreement on
# the same image, model, heights and grid.
#   bash bench/ortho_gdalwarp.sh [OUT]      (default OUT: a new folder under /tmp; BIN (build/bin), THREADS (2))
# Cases: the Marseille triplet at a flat height (150 m above the ellipsoid) and on a DEM made here (a
# smooth relief of +-60 m about 150 m, 2 m posting, UTM 31N, heights above the ellipsoid: no DEM of
# Marseille is in ../shared), and the twelve Jacksonville crops on lidar_dsm_utm17n.tif (heights above
# the ellipsoid). For each image: tp-ortho writes its ortho on its own grid (the image's footprint, the
# default pixel size); gdalwarp is run on that very grid, read back with gdalinfo (-t_srs EPSG:N, -te, -tr);
# then the share of the pixels valid in both whose every band differs by at most 1 grey level, and the
# pixels valid in one only.
# Conventions matched explicitly:
#   - pixels: the RPC00B model's (0, 0) is the centre of the top-left pixel, which is tpkit's; GDAL's RPC
#     transformer adds the half pixel itself to reach its corner-based pixel/line (alg/gdal_rpc.cpp), so
#     both read the model as it is stored (GeoTIFF tag 50844);
#   - heights: tp-ortho --height H is H m above the ellipsoid = gdalwarp -to RPC_HEIGHT=H; tp-ortho --dem D
#     = gdalwarp -to RPC_DEM=D with RPC_DEMINTERPOLATION=bilinear (GDAL's default, said here), both
#     bilinear between the DEM's pixel centres, heights used as stored (the DEMs here are ellipsoidal: no
#     vertical datum in their keys, so neither tp-ortho nor GDAL's RPC_DEM_APPLY_VDATUM_SHIFT shifts them);
#   - resampling: -r bilinear, the 2 x 2 interpolation between pixel centres. GDAL's warper widens its
#     kernel by the ratio of each processing chunk's source window to its destination window (XSCALE,
#     YSCALE): for an image not aligned with the grid that window's bounding box is larger than the chunk,
#     and GDAL reads it as a downsampling (a rotated Marseille view: 56% of the pixels within 1 grey level
#     of 16 bits, up to 154 apart, where the geometry agrees to 0.001 px); -wo XSCALE=1 -wo YSCALE=1 is the
#     plain kernel, which tp-ortho's is at the same resolution;
#   - nodata: 0 out (-dstnodata 0, tp-ortho's default for integer samples); a pixel is valid when a band
#     is not 0;
#   - exactness: gdalwarp -et 0 (its transformer exact at every pixel, as tp-ortho's is).
# Pixels valid in one output only are counted, not compared: tp-ortho needs the DEM's 4 cells around a
# point (tp-rpc and rpc-adjust read DEMs so), GDAL also samples the DEM's outer half pixel (a strip about
# one output pixel wide along the DSM's edges); and gdalwarp leaves nodata where its transformer fails
# ("ERROR 1: Point outside of projection domain"), e.g. a band 30 rows high along the DSM's north edge in
# JAX_068_018's ortho, where the model sees the image and the DSM has heights.
# Two gdalwarp runs per image: "matched" (-et 0, XSCALE = YSCALE = 1), the agreement figure; "default"
# (gdalwarp as users run it: -et 0.125, an approximating transformer interpolating pixel positions along
# rows, and the chunk-wise kernel scale), its agreement given too. Both with -multi -wo NUM_THREADS=$THREADS,
# tp-ortho with --threads $THREADS. Times: wall clock and CPU (user + system) of each whole command
# (process start, reading, writing: tp-ortho deflate-compressed tiles, gdalwarp an uncompressed file, its
# default); Mpx/s counts output pixels. On a machine shared with other work, the CPU time is the figure
# that compares; wall clock is given as measured.
set -euo pipefail
if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'; exit 0; fi
cd "$(dirname "$0")/.."
BIN=$(cd "${BIN:-build/bin}" && pwd)
export PATH="$BIN:$PATH"
THREADS=${THREADS:-2}
SHARED=$(cd ../shared/data && pwd)
OUT=${1:-$(mktemp -d /tmp/tpkit-ortho-gdalwarp.XXXXXX)}
mkdir -p "$OUT"
cd "$OUT"
# the system Python: GDAL's bindings and numpy come with gdal-bin (python3-gdal), not in another Python on PATH
PY=/usr/bin/python3
[ -x $PY ] || PY=$(command -v python3)
for t in gdalwarp gdalinfo gdal_translate bc $PY; do
  command -v $t >/dev/null || { echo "ortho_gdalwarp: $t is missing (bash scripts/install-deps.sh --test installs gdal-bin)" >&2; exit 1; }
done
$PY -c 'from osgeo import gdal; import numpy' 2>/dev/null ||
  { echo "ortho_gdalwarp: python3-gdal and python3-numpy are missing (gdal-bin brings them)" >&2; exit 1; }

# The Marseille DEM: around the triplet's centre (tp-rpc, UTM), 1400 x 1400 m at 2 m, as an ESRI ASCII grid
# turned into a GeoTIFF by gdal_translate.
marseille_dem() {
  read -r e0 n0 _ < <(echo "511.5 511.5 150" | tp-rpc -q localize "$SHARED/pleiades-marseille/img_01.tif" --crs utm)
  awk -v e0="$e0" -v n0="$n0" 'BEGIN {
    n = 700; d = 2; xll = int(e0 - n * d / 2); yll = int(n0 - n * d / 2)
    printf "ncols %d\nnrows %d\nxllcorner %d\nyllcorner %d\ncellsize %d\nNODATA_value -9999\n", n, n, xll, yll, d
    pi = 3.14159265358979
    for (r = 0; r < n; r++) { line = ""
      for (c = 0; c < n; c++) { e = xll + (c + 0.5) * d; y = yll + (n - r - 0.5) * d
        h = 150 + 40 * sin(2 * pi * (e - xll) / 530) * cos(2 * pi * (y - yll) / 410) + 20 * sin(2 * pi * (e + y - xll - yll) / 170)
        line = line sprintf(" %.3f", h) }
      print substr(line, 2) } }' > marseille_dem.asc
  gdal_translate -q -a_srs EPSG:32631 -co TILED=YES marseille_dem.asc marseille_dem.tif
}

# compare A.tif B.tif: "valid_both within1 pct_within1 only_a only_b max_diff"
compare() {
  $PY - "$1" "$2" <<'PY'
import sys
import numpy as np
from osgeo import gdal
a = gdal.Open(sys.argv[1]); b = gdal.Open(sys.argv[2])
A = a.ReadAsArray().astype(np.float64); B = b.ReadAsArray().astype(np.float64)
if A.ndim == 2: A = A[None]; B = B[None]
va = np.any(A != 0, axis=0); vb = np.any(B != 0, axis=0)
both = va & vb
d = np.abs(A - B).max(axis=0)[both]
n = int(both.sum()); w = int((d <= 1).sum())
print(n, w, "%.3f" % (100.0 * w / max(n, 1)), int((va & ~vb).sum()), int((vb & ~va).sum()), int(d.max()) if n else 0)
PY
}

# timed FILE CMD...: runs CMD, appends "wall cpu" (seconds) to FILE
timed() {
  local f=$1
  shift
  /usr/bin/time -f "%e %U %S" -o "$f.t" "$@"
  awk '{ print $1, $2 + $3 }' "$f.t" >> "$f"
}
sum() { awk -v k="$2" '{ s += $k } END { printf "%.3f", s }' "$1"; }

# case NAME HEIGHTS_TP HEIGHTS_GDAL IMAGE...
case_run() {
  local name=$1 tp_h=$2 gd_h=$3
  shift 3
  local px=0
  mkdir -p "$name"
  rm -f "$name"/times.* "$name"/agree.*
  for img in "$@"; do
    local stem info epsg w h x0 y0 g te
    stem=$(basename "${img%.*}")
    # shellcheck disable=SC2086
    timed "$name/times.tp" tp-ortho -q "$img" $tp_h --threads "$THREADS" -o "$name/$stem.tp.tif"
    info=$(gdalinfo "$name/$stem.tp.tif")
    epsg=$(echo "$info" | grep -oE 'ID\["EPSG",[0-9]+\]\]$' | tail -n 1 | grep -oE '[0-9]+')
    read -r w h < <(echo "$info" | sed -nE 's/^Size is ([0-9]+), ([0-9]+)$/\1 \2/p')
    read -r x0 y0 < <(echo "$info" | sed -nE 's/^Origin = \(([-0-9.e+]+),([-0-9.e+]+)\)$/\1 \2/p')
    g=$(echo "$info" | sed -nE 's/^Pixel Size = \(([-0-9.e+]+),.*$/\1/p')
    te=$(echo "$x0 $y0 $w $h $g" | awk '{ printf "%.6f %.6f %.6f %.6f", $1, $2 - $4 * $5, $1 + $3 * $5, $2 }')
    local common=(-q -overwrite -rpc -r bilinear -t_srs "EPSG:$epsg" -te $te -tr "$g" "$g" -dstnodata 0 -multi -wo "NUM_THREADS=$THREADS"
                  -to RPC_DEMINTERPOLATION=bilinear)
    # shellcheck disable=SC2086
    timed "$name/times.matched" gdalwarp "${common[@]}" $gd_h -et 0 -wo XSCALE=1 -wo YSCALE=1 "$img" "$name/$stem.matched.tif"
    # shellcheck disable=SC2086
    timed "$name/times.default" gdalwarp "${common[@]}" $gd_h "$img" "$name/$stem.default.tif"
    local m d
    m=$(compare "$name/$stem.tp.tif" "$name/$stem.matched.tif")
    d=$(compare "$name/$stem.tp.tif" "$name/$stem.default.tif")
    echo "$m" >> "$name/agree.matched"
    echo "$d" >> "$name/agree.default"
    printf '  %-16s %4d x %-4d EPSG:%s %g m: within 1 grey level: matched %s%% of %s (max %s), default %s%% (max %s); valid in one only: %s, %s\n' \
      "$stem" "$w" "$h" "$epsg" "$g" "$(echo $m | cut -d' ' -f3)" "$(echo $m | cut -d' ' -f1)" "$(echo $m | cut -d' ' -f6)" \
      "$(echo $d | cut -d' ' -f3)" "$(echo $d | cut -d' ' -f6)" "$(echo $m | cut -d' ' -f4)" "$(echo $m | cut -d' ' -f5)"
    px=$((px + w * h))
  done
  for k in matched default; do
    awk -v name="$name" -v k=$k '{ nb += $1; nw += $2; oa += $4; ob += $5; if ($6 > md) md = $6 }
      END { printf "%s: gdalwarp %s: %.2f%% of %d pixels valid in both within 1 grey level (max difference %d); valid in one only: tp-ortho %d, gdalwarp %d\n", name, k, 100 * nw / nb, nb, md, oa, ob }' "$name/agree.$k"
  done
  local mp
  mp=$(echo "$px / 1000000" | bc -l)
  for k in tp matched default; do
    local wall cpu label
    wall=$(sum "$name/times.$k" 1)
    cpu=$(sum "$name/times.$k" 2)
    case $k in tp) label="tp-ortho        " ;; matched) label="gdalwarp matched" ;; default) label="gdalwarp default" ;; esac
    printf '%s: %s %.2f Mpx: wall %6.2f s (%5.2f Mpx/s), CPU %6.2f s (%5.2f Mpx per CPU s)\n' "$name" "$label" "$mp" "$wall" \
      "$(echo "$mp / $wall" | bc -l)" "$cpu" "$(echo "$mp / $cpu" | bc -l)"
  done
}

echo "== $(gdalwarp --version | cut -d, -f1); $(tp-ortho --version); $THREADS threads; $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
M=$SHARED/pleiades-marseille
J=$SHARED/wv3-jacksonville
marseille_dem
case_run marseille-flat "--height 150" "-to RPC_HEIGHT=150" "$M"/img_0{1,2,3}.tif
case_run marseille-dem "--dem marseille_dem.tif" "-to RPC_DEM=marseille_dem.tif" "$M"/img_0{1,2,3}.tif
case_run jacksonville-lidar "--dem $J/lidar_dsm_utm17n.tif" "-to RPC_DEM=$J/lidar_dsm_utm17n.tif" "$J"/JAX_068_0*_RGB.tif
