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
