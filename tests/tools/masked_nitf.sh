#!/bin/bash
# Writes a NITF 2.1 image that declares ROWS x COLS 16-bit pixels in blocks of BLOCK x BLOCK, all of them
# left out of its block mask (IC = NM, every offset 0xFFFFFFFF; one byte after the mask, as the image data
# may not end at it): a few kilobytes declaring any size, as MIL-STD-2500C allows (fields laid out as
# tests/unit/core/nitf_image_test.cpp assembles them).
# Usage: masked_nitf.sh OUT ROWS COLS BLOCK
set -eu
out=$1; rows=$2; cols=$3; block=$4
nbpr=$(( (cols + block - 1) / block )); nbpc=$(( (rows + block - 1) / block )); n=$(( nbpr * nbpc ))
be32() { printf "\\x$(printf %02x $(( ($1 >> 24) & 255 )))\\x$(printf %02x $(( ($1 >> 16) & 255 )))\\x$(printf %02x $(( ($1 >> 8) & 255 )))\\x$(printf %02x $(( $1 & 255 )))"; }
sub() {
  printf 'IM%-10s20261203000000%-17s%-80sU%-166s0%-42s' t '' '' '' ''
  printf '%08d%08d%-3s%-8s%-8s16R 0NM1' "$rows" "$cols" INT MONO VIS
  printf '%-2s%-6sN%-3s0' M '' ''
  printf '0B%04d%04d%04d%04d16' "$nbpr" "$nbpc" "$block" "$block"
  printf '0010000000000000''1.0 ''00000''00000'
}
data() {
  be32 $(( 12 + 4 * n )); printf '\x00\x04\x00\x00\x00\x10\x00\x07'
  for ((k = 0; k < n; ++k)); do printf '\xff\xff\xff\xff'; done
  printf '\x00'
}
sublen=$(sub | wc -c); datalen=$(( 12 + 4 * n + 1 )); hl=$(( 360 + 3 + 16 + 25 ))
{
  printf 'NITF02.1003BF01%-10s20261203000000%-80sU%-166s00000000000\x00\x00\x00%-42s' t '' '' ''
  printf '%012d%06d001%06d%010d000000000000000''00000''00000' $(( hl + sublen + datalen )) "$hl" "$sublen" "$datalen"
  sub
  data
} > "$out"
