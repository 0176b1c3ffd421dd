# docs/blocks.md: Jacksonville, about 2700 tracks of 2 to 4 views (views dropped by tp-chain's RPC
# check), 0.85 px before and about 0.15 px after, no track flagged, the points about 0.1 m above the lidar
# DSM in median (NMAD about 0.5 m); the synthetic block's tracks of 2 to 6 views, every image adjusted, a ground point
# per track
n=$(records jax/tracks.tracks)
within "$n" 2450 2950 || fail "jax/tracks.tracks: $n tracks, the page says about 2700"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]*$' jax/tracks.tracks || fail "jax/tracks.tracks: not tracks of 2 to 4 views"
before=$(header rms_before_px jax/adjusted/rpc.residuals) after=$(header rms_after_unflagged_px jax/adjusted/rpc.residuals)
within "$before" 0.75 1.0 && within "$after" 0.12 0.19 || fail "jax: rms $before px before, $after px after; the page says 0.85 and about 0.15"
grep -q '^# rpc_check: .* 6 image pairs, .* [1-9][0-9]* views dropped' jax/tracks.tracks || fail "jax/tracks.tracks: no RPC check of the 6 pairs dropping views"
flagged=$(header flagged_tracks jax/adjusted/rpc.residuals)
within "$flagged" 0 5 || fail "jax: $flagged flagged tracks, the page says none"
read -r median nmad < <(awk '!/^#/ && $1 == 0 && $2 == 0 { print $6, $7 }' jax.dz)
within "${median:-9}" -0.2 0.4 && within "${nmad:-9}" 0.4 0.65 || fail "jax.dz: median ${median:-?} m, NMAD ${nmad:-?} m; the page says about 0.1 and 0.5 m"
grep -q '^# tracks_by_views: 2:[0-9]* 3:[0-9]* 4:[0-9]* 5:[0-9]* 6:' block-run/tracks.tracks ||
  fail "block-run/tracks.tracks: $(grep '^# tracks_by_views' block-run/tracks.tracks), tracks of 2 to 6 views expected"
rms=$(header rms_after_unflagged_px block-run/adjusted/rpc.residuals)
within "$rms" 0 0.06 || fail "block-run: rpc-adjust rms after $rms px, above the 0.06 px of a block adjusted to its tie points"
[ "$(records block-run/ground.points)" = "$(records block-run/tracks.tracks)" ] || fail "block-run/ground.points: not a point per track"
