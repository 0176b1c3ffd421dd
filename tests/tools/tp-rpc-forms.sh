#!/bin/bash
# tp-rpc through an OSSIM .geom and through an image with a GDAL .aux.xml beside it (tests/tools/tp-rpc.cmake):
# a tp-synth view's _rpc.txt is rewritten here by hand (awk, not tpkit's writers) as an ossimRpcModel
# keyword list and as the RPC metadata domain of img.tif.aux.xml, img.tif an image without a model of its
# own; ground points over the view project to the txt model's pixels in both, to the last digit (the
# offsets are the same numbers in the three forms: RPC00B, OSSIM and GDAL share (0, 0) at the centre of
# the top-left pixel).
set -euo pipefail
tp-synth --out s --size 300 --seed 2 --relief 10 --threads 2 --supersample 1 >/dev/null
txt=s/view1_rpc.txt
# OSSIM's names: lower case, LONG_ long_, ERR_BIAS bias_error; coefficient n (1..20) is _coeff_(n - 1), 2 digits
awk -F': *' 'BEGIN { print "type:  ossimRpcModel"; print "polynomial_format:  B" }
  $1 == "ERR_BIAS" { print "bias_error:  " $2; next }
  $1 == "ERR_RAND" { print "rand_error:  " $2; next }
  $1 ~ /_COEFF_/ { split($1, a, "_"); printf "%s_%s_coeff_%02d:  %s\n", tolower(a[1]), tolower(a[2]), a[4] - 1, $2; next }
  { print tolower($1) ":  " $2 }' "$txt" > m.geom
# GDAL's RPC domain: the same keys, each polynomial's 20 coefficients in one value, beside statistics
cp s/truth.dem.tif img.tif
awk -F': *' 'BEGIN { print "<PAMDataset>"; print "  <Metadata domain=\"RPC\">" }
  $1 ~ /_COEFF_/ { k = $1; sub(/_[0-9]+$/, "", k); c[k] = c[k] $2 " "; next }
  { printf "    <MDI key=\"%s\">%s</MDI>\n", $1, $2 }
  END { for (k in c) printf "    <MDI key=\"%s\">%s</MDI>\n", k, c[k]
        print "  </Metadata>"
        print "  <PAMRasterBand band=\"1\"><Metadata><MDI key=\"STATISTICS_MEAN\">100.5</MDI></Metadata></PAMRasterBand>"
        print "</PAMDataset>" }' "$txt" > img.tif.aux.xml
# ground points over the view: a grid of its pixels localized at three heights through the txt model
awk 'BEGIN { for (i = 0; i <= 6; i++) for (j = 0; j <= 6; j++) for (h = 90; h <= 110; h += 10) print 20 + 43 * i, 20 + 43 * j, h }' > px
tp-rpc -q localize "$txt" -i px > ground
tp-rpc -q project "$txt" -i ground > by-txt
tp-rpc project m.geom -i ground > by-geom 2> geom.log
tp-rpc project img.tif -i ground > by-aux 2> aux.log
cmp by-txt by-geom && echo "geom: $(wc -l < by-geom) points, same pixels; $(grep -o 'm.geom (geom)' geom.log)"
cmp by-txt by-aux && echo "aux: $(wc -l < by-aux) points, same pixels; $(grep -o 'img.tif.aux.xml (aux)' aux.log)"
