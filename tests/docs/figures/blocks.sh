# docs/blocks.md: Jacksonville, about 3500 chained tracks and about 3200 refined, of 2 to 4 views (views
# dropped by tp-chain's RPC check), about 1400 refined ones on all four dates, 0.92 px before and about
# 0.11 px after, no track flagged, the points within a couple of metres of the lidar DSM in median (NMAD
# about 0.4 m); the synthetic block's tracks of 2 to 6 views, every image adjusted, a ground point per
# refined track
n=$(records jax/tracks.tracks)
within "$n" 3200 3800 || fail "jax/tracks.tracks: $n tracks, the page says about 3500"
n=$(records jax/refined.tracks)
within "$n" 2900 3500 || fail "jax/refined.tracks: $n tracks, the page says about 3200"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]*$' jax/refined.tracks || fail "jax/refined.tracks: not tracks of 2 to 4 views"
four=$(sed -n 's/^# tracks_by_views: .* 4:\([0-9]*\)$/\1/p' jax/refined.tracks)
within "${four:-0}" 1200 1600 || fail "jax/refined.tracks: ${four:-?} tracks on all four dates, the page says about 1400"
before=$(header rms_before_px jax/adjusted/rpc.residuals) after=$(header rms_after_unflagged_px jax/adjusted/rpc.residuals)
within "$before" 0.8 1.05 && within "$after" 0.08 0.14 || fail "jax: rms $before px before, $after px after; the page says 0.92 and about 0.11"
grep -q '^# rpc_check: .* 6 image pairs, .* [1-9][0-9]* views dropped' jax/tracks.tracks || fail "jax/tracks.tracks: no RPC check of the 6 pairs dropping views"
flagged=$(header flagged_tracks jax/adjusted/rpc.residuals)
within "$flagged" 0 5 || fail "jax: $flagged flagged tracks, the page says none"
read -r median nmad < <(awk '!/^#/ && $1 == 0 && $2 == 0 { print $6, $7 }' jax.dz)
within "${median:-9}" -2.5 2.5 && within "${nmad:-9}" 0.3 0.5 || fail "jax.dz: median ${median:-?} m, NMAD ${nmad:-?} m; the page says within a couple of metres and about 0.4 m"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), tracks of 2 to 6 views expected"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/refined.tracks)" ] || fail "block-run/ground.points: not a point per refined track"
