# docs/triplets.md: about 8000 triplets and 9000 two-view tracks, about 0.09 px over all triplets, and
# the held-out half of the inliers about as close as the fitted half (0.08 and 0.08 px)
n=$(records triplet.tracks)
within "$n" 7700 8300 || fail "triplet.tracks: $n triplets, the page says about 8000"
two=$(sed -n 's/^# tracks_by_views: 2:\([0-9]*\) .*/\1/p' all.tracks)
within "${two:-0}" 8500 9500 || fail "all.tracks: ${two:-no} two-view tracks, the page says about 9000"
rmse=$(header rmse_px fit-ml.eval)
within "$rmse" 0.075 0.10 || fail "fit-ml.eval: rmse $rmse px, the page says about 0.09 px"
fit=$(header rms_after_px adjusted-half/rpc.residuals) check=$(header check_rms_px adjusted-half/rpc.residuals)
within "$fit" 0.07 0.09 && within "$check" 0.07 0.095 ||
  fail "adjusted-half: fit $fit px, held out $check px; the page says about 0.08 and 0.08"
