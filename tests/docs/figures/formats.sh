# docs/formats.md: the crop's model puts the point 256 px less in x and y; the NITF copy within 0.005 px
# of the GeoTIFF; WorldView-3's NITF as GDAL reads it
read -r x0 y0 < <(grep ' p1$' "$log" | sed -n 1p)
read -r xc yc < <(grep ' p1$' "$log" | sed -n 3p)
read -r xn yn < <(grep ' p1$' "$log" | sed -n 4p)
within "$(awk -v a="$x0" -v b="$xc" -v c="$y0" -v d="$yc" 'BEGIN { print (a - b - 256) ^ 2 + (c - d - 256) ^ 2 }')" 0 1e-12 ||
  fail "crop-01.tif: ($xc, $yc), not 256 px less than ($x0, $y0)"
within "$(awk -v a="$x0" -v b="$xn" -v c="$y0" -v d="$yn" 'BEGIN { print sqrt((a - b) ^ 2 + (c - d) ^ 2) }')" 0 0.0053 ||
  fail "img_01.ntf: ($xn, $yn), not within 0.005 px of ($x0, $y0)"
grep -q '^249.9965647[0-9]* 249.987913[0-9]* 31$' "$log" || fail "wv3_20.NTF: not GDAL's 249.996564797 249.98791348"
