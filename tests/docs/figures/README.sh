# README.md, "A five-minute tour": the triplets, the fit's RMSE, rpc-adjust before and after, a ground
# point per inlier track and the report written.
n=$(records triplet.tracks)
within "$n" 7700 8300 || fail "triplet.tracks: $n triplets, the page says about 8000"
rmse=$(header rmse_px fit-ml.eval)
within "$rmse" 0.075 0.10 || fail "fit-ml.eval: rmse $rmse px, the page says about 0.09 px"
# "by 0.56 px RMS; adjusted, by 0.085 px"
read -r before after < <(sed -n 's/^rpc-adjust: .*model affine: rms \([0-9.]*\) px before, \([0-9.]*\) px after.*/\1 \2/p' "$log")
within "${before:-0}" 0.55 0.58 && within "${after:-0}" 0.080 0.090 ||
  fail "rpc-adjust: rms ${before:-?} px before, ${after:-?} px after; the page says 0.56 and 0.085"
[ "$(records marseille.points)" = "$(records inliers.tracks)" ] || fail "marseille.points: not a ground point per inlier track"
grep -q '<svg' marseille.html || fail "marseille.html: no figure"
