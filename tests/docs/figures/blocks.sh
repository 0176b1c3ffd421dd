# docs/blocks.md: Jacksonville, about 3200 tracks of 2 to 4 views (views dropped by tp-chain's RPC
# check), 0.87 px before and about 0.18 px after, no track flagged, the points within a couple of metres
# of the lidar DSM in median (NMAD about 0.5 m); the synthetic block's tracks of 2 to 6 views, every image adjusted, a ground point
# per track
n=$(records jax/tracks.tracks)
within "$n" 2900 3500 || fail "jax/tracks.tracks: $n tracks, the page says about 3200"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]*$' jax/tracks.tracks || fail "jax/tracks.tracks: not tracks of 2 to 4 views"
before=$(header rms_before_px jax/adjusted/rpc.residuals) after=$(header rms_after_unflagged_px jax/adjusted/rpc.residuals)
within "$before" 0.75 1.0 && within "$after" 0.14 0.21 || fail "jax: rms $before px before, $after px after; the page says 0.87 and about 0.18"
grep -q '^# rpc_check: .* 6 image pairs, .* [1-9][0-9]* views dropped' jax/tracks.tracks || fail "jax/tracks.tracks: no RPC check of the 6 pairs dropping views"
flagged=$(header flagged_tracks jax/adjusted/rpc.residuals)
within "$flagged" 0 5 || fail "jax: $flagged flagged tracks, the page says none"
read -r median nmad < <(awk '!/^#/ && $1 == 0 && $2 == 0 { print $6, $7 }' jax.dz)
within "${median:-9}" -2.5 2.5 && within "${nmad:-9}" 0.4 0.65 || fail "jax.dz: median ${median:-?} m, NMAD ${nmad:-?} m; the page says within a couple of metres and about 0.5 m"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), tracks of 2 to 6 views expected"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/tracks.tracks)" ] || fail "block-run/ground.points: not a point per track"
