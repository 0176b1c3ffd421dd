# docs/interop.md: every form written, and the pairs read back from COLMAP's database hold the records
# they were written from
for f in run/run-img_01__img_02.match Homol/Pastisimg_01.tif/img_02.tif.dat colmap/database.db matches/matches.f.txt matches/sfm_data.json; do
  [ -s "$f" ] || fail "$f: not written"
done
for p in 1-2 1-3 2-3; do
  back=from-colmap/img_0${p%-*}__img_0${p#*-}.matches
  [ -f "$back" ] && [ "$(records "$back")" = "$(records "pairs/pair-$p.matches")" ] ||
    fail "$back: not the records of pairs/pair-$p.matches"
done
