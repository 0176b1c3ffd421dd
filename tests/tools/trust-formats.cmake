# Issue 50, the format readers: NITF RPC00B fields and TREs, JPEG 2000 corruption, the XML forms of an
# RPC model (DIMAP, GDAL .aux.xml), tag 50844, the peer formats (COLMAP, OpenMVG) and the pair geometry
# of a region run. Each case: what a forged file did before (taken without a word), refused or read right.
set(_wv3 "$SHARED/data/nitf-wv3")

# Item 12: an RPC00B field in hexadecimal (LINE_OFF "0x00fa", read as 250 by strtod) is not STDI-0002's
# form (digits): refused, naming the field.
tpkit_tool_test(trust-formats.nitf-hex-field
  COMMAND "LC_ALL=C sed 's/0000.330174952074/0000.330x00fa2074/' ${_wv3}/wv3_20.NTF > hex.ntf && cmp -s hex.ntf ${_wv3}/wv3_20.NTF@SEMI@ test $? = 1 && echo '-58.52 -34.55 20' | tp-rpc project hex.ntf -o p.txt"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: hex.ntf: RPC00B TRE: LINE_OFF [(]characters 16 to 21[)] is '0x00fa', not a number of its form [(]digits[)]"
  NO_FILE p.txt)

# Item 17: a tag 50844 whose 92 doubles run past the end of the file (libtiff passes over it as if it
# were absent) was reported as "no tag 50844": it is a corrupt tag, said so with where it lies.
tpkit_tool_test(trust-formats.tag-50844-past-the-end
  COMMAND "tp-synth --out s --size 128 --seed 1 --supersample 1 --relief 10 >/dev/null 2>&1 && head -c $(( $(wc -c < s/view1.tif) - 100 )) s/view1.tif > cut.tif && echo '0 0 0' | tp-rpc project cut.tif"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: cut.tif: RPC tag 50844 is corrupt: its 92 values of TIFF type 12 [(]736 bytes from byte [0-9]+[)] run past the end of the file [(][0-9]+ bytes[)]: give the model with --rpc")

# Item 14: one pair given twice (the same file, or its two directions) was written twice into OpenMVG's
# matches.f.txt; COLMAP refused it only when writing the database. Both peer formats hold one set of
# matches per pair: refused before anything is written.
set(_ab "printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: B.tif 90 90\\n# columns: id1 x1 y1 id2 x2 y2\\n1 10.25 20.5 7 11.75 21.125\\n' > ab.m")
tpkit_tool_test(trust-formats.openmvg-pair-twice
  COMMAND "${_ab} && tp-convert --to openmvg ab.m ab.m -o mvg"
  EXPECT_FAIL STDERR_MATCH "tp-convert: ab.m: pairs A.tif and B.tif, as ab.m does: COLMAP and OpenMVG hold one set of matches per pair"
  NO_FILE mvg/matches.f.txt)
tpkit_tool_test(trust-formats.colmap-pair-both-ways
  COMMAND "${_ab} && printf '# tpkit matches 1\\n# image1: B.tif 90 90\\n# image2: A.tif 100 80\\n# columns: id1 x1 y1 id2 x2 y2\\n7 11.75 21.125 1 10.25 20.5\\n' > ba.m && tp-convert --to colmap ab.m ba.m -o col"
  EXPECT_FAIL STDERR_MATCH "tp-convert: ba.m: pairs B.tif and A.tif, as ab.m does"
  NO_FILE col/database.db)

# Item 12: a JPEG 2000 NITF whose codestream lacks tiles (cut after its first two tile-parts, EOC after
# them, LI and FL made to agree) decoded them as 0 without a word: refused, naming the tile. Bytes flipped
# inside a tile's data cannot be seen (no checksum: tpkit-formats(5)).
tpkit_tool_test(trust-formats.j2k-tiles-missing
  COMMAND "tp-rpc -q crop ${_wv3}/wv3_20.NTF --compression j2k --block 256 -o j.ntf && li=$(head -c 379 j.ntf | tail -c 10) && start=$(( $(wc -c < j.ntf) - 10#$li )) && cut=$(od -An -v -tx1 j.ntf | tr -s ' ' '\\n' | awk 'NF { b[n++] = $1 } END { for (i = 0@SEMI@ i + 5 < n@SEMI@ i++) if (b[i] b[i + 1] b[i + 2] b[i + 3] b[i + 4] b[i + 5] == \"ff90000a0002\") { print i@SEMI@ exit } }') && { head -c 342 j.ntf@SEMI@ printf '%012d' $(( cut + 2 ))@SEMI@ head -c 369 j.ntf | tail -c 15@SEMI@ printf '%010d' $(( cut + 2 - start ))@SEMI@ head -c $cut j.ntf | tail -c +380@SEMI@ printf '\\xff\\xd9'@SEMI@ } > cut.ntf && tp-rpc crop cut.ntf --window 0 200 100 100 -o c.tif"
  EXPECT_FAIL STDERR_MATCH "tp-rpc: cut.ntf: JPEG 2000: tile 2 [(]of 4[)] is not in the codestream" NO_FILE c.tif)

# Item 14: a pair geometry whose map is singular (a11 a12 a21 a22 zeroed) sent every region to one point
# of image 2 and wrote zero matches, blaming the models: refused as it is read, with its line.
tpkit_tool_test(trust-formats.region-geometry-singular
  COMMAND "tp-synth --out s --size 640 --seed 4 --threads 2 --supersample 1 >/dev/null && tp-match -q --write-geometry g s/view1.tif s/view2.tif && awk '/^#/ { print@SEMI@ next } { $1 = 0@SEMI@ $2 = 0@SEMI@ $4 = 0@SEMI@ $5 = 0@SEMI@ print }' g > z && tp-match --geometry z --region 0 0 100 100 s/view1.tif s/view2.tif -o a.m"
  EXPECT_FAIL STDERR_MATCH "tp-match: z:[0-9]+: the map a11 .. a22 is singular or nearly [(]singular values 0 and 0[)]" NO_FILE a.m)
# Item 14, the region read by tp-merge: a file whose region line is no window (width 0) ranked every
# record of its file as outside it: refused.
tpkit_tool_test(trust-formats.merge-region-empty
  COMMAND "printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: B.tif 90 90\\n# region: 0 0 0 80 (x0 y0 width height)\\n# columns: id1 x1 y1 id2 x2 y2\\n1 10 20 7 11 21\\n' > a.m && printf '# tpkit matches 1\\n# image1: A.tif 100 80\\n# image2: B.tif 90 90\\n# region: 50 0 50 80 (x0 y0 width height)\\n# columns: id1 x1 y1 id2 x2 y2\\n2 60 20 8 61 21\\n' > b.m && tp-merge a.m b.m -o m.m"
  EXPECT_FAIL STDERR_MATCH "tp-merge: a.m: region metadata 0 0 0 80: not a window of pixels" NO_FILE m.m)
