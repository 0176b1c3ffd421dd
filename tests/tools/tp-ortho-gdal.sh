#!/usr/bin/env bash
# tp-ortho checked by GDAL, the peer (installed by scripts/install-deps.sh --test; missing is a failure, not
# a skip):
#   tp-ortho-gdal.sh info ORTHO.tif          prints "EPSG:N W H X0 Y0 GSD" as gdalinfo reads them
#   tp-ortho-gdal.sh agree ORTHO.tif IMAGE GDALWARP_OPTION...
#       runs gdalwarp -rpc -r bilinear -et 0 -wo XSCALE=1 -wo YSCALE=1 (the plain bilinear kernel: see
#       bench/ortho_gdalwarp.sh) on ORTHO's grid (gdalinfo) with the options given (-to RPC_DEM=...)
#       and prints "PCT% within 1 of N" (pixels valid in both, every band within 1 grey level)
set -euo pipefail
# the system Python, which has GDAL's bindings and numpy (python3-gdal, brought by gdal-bin), before another on PATH
PY=/usr/bin/python3
[ -x $PY ] || PY=$(command -v python3)
for t in gdalinfo gdalwarp $PY; do
  command -v $t >/dev/null || { echo "tp-ortho-gdal: $t is missing: bash scripts/install-deps.sh --test installs gdal-bin" >&2; exit 1; }
done
info() {
  local i epsg
  i=$(gdalinfo "$1")
  epsg=$(echo "$i" | grep -oE 'ID\["EPSG",[0-9]+\]\]$' | tail -n 1 | grep -oE '[0-9]+')
  echo "EPSG:$epsg $(echo "$i" | sed -nE 's/^Size is ([0-9]+), ([0-9]+)$/\1 \2/p') $(echo "$i" | sed -nE 's/^Origin = \(([-0-9.e+]+),([-0-9.e+]+)\)$/\1 \2/p') $(echo "$i" | sed -nE 's/^Pixel Size = \(([-0-9.e+]+),.*$/\1/p')"
}
case $1 in
  info) info "$2" ;;
  agree)
    ortho=$2 image=$3
    shift 3
    read -r crs w h x0 y0 g < <(info "$ortho")
    te=$(echo "$x0 $y0 $w $h $g" | awk '{ printf "%.6f %.6f %.6f %.6f", $1, $2 - $4 * $5, $1 + $3 * $5, $2 }')
    # shellcheck disable=SC2086
    gdalwarp -q -overwrite -rpc -et 0 -wo XSCALE=1 -wo YSCALE=1 -r bilinear -t_srs "$crs" -te $te -tr "$g" "$g" -dstnodata 0 "$@" "$image" gdalwarp.tif
    $PY - "$ortho" gdalwarp.tif <<'PY'
import sys
import numpy as np
from osgeo import gdal
A = gdal.Open(sys.argv[1]).ReadAsArray().astype(np.float64)
B = gdal.Open(sys.argv[2]).ReadAsArray().astype(np.float64)
if A.ndim == 2: A = A[None]; B = B[None]
both = np.any(A != 0, axis=0) & np.any(B != 0, axis=0)
n = int(both.sum())
w = int((np.abs(A - B).max(axis=0)[both] <= 1).sum())
print("%.1f%% within 1 of %d" % (100.0 * w / max(n, 1), n))
PY
    ;;
  *) echo "tp-ortho-gdal: info | agree" >&2; exit 2 ;;
esac
