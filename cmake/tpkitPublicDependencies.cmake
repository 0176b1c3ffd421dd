# The libraries tpkit's own libraries link (every one a Debian package, see scripts/install-deps.sh):
# found the same way when tpkit is built (cmake/Dependencies.cmake) and when an installed tpkit is used
# (tpkitConfig.cmake installs this file), so that one place knows how each is found.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(CLI11 CONFIG QUIET)
if(NOT CLI11_FOUND AND NOT TARGET CLI11::CLI11)
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp REQUIRED)
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  set_target_properties(CLI11::CLI11 PROPERTIES INTERFACE_INCLUDE_DIRECTORIES ${CLI11_INCLUDE_DIR})
endif()
find_package(TIFF REQUIRED)
find_package(OpenCV REQUIRED COMPONENTS core imgproc features2d flann calib3d video)
find_package(Ceres REQUIRED)
find_package(nanoflann CONFIG QUIET)
if(NOT nanoflann_FOUND AND NOT TARGET nanoflann::nanoflann)
  find_path(NANOFLANN_INCLUDE_DIR nanoflann.hpp REQUIRED)
  add_library(nanoflann::nanoflann INTERFACE IMPORTED)
  set_target_properties(nanoflann::nanoflann PROPERTIES INTERFACE_INCLUDE_DIRECTORIES ${NANOFLANN_INCLUDE_DIR})
endif()
find_package(GeographicLib CONFIG QUIET)
if(NOT GeographicLib_FOUND AND NOT TARGET GeographicLib::GeographicLib)
  find_path(GEOGRAPHICLIB_INCLUDE_DIR GeographicLib/Geodesic.hpp REQUIRED)
  find_library(GEOGRAPHICLIB_LIBRARY NAMES Geographic GeographicLib REQUIRED)
  add_library(GeographicLib::GeographicLib UNKNOWN IMPORTED)
  set_target_properties(GeographicLib::GeographicLib PROPERTIES
    IMPORTED_LOCATION ${GEOGRAPHICLIB_LIBRARY} INTERFACE_INCLUDE_DIRECTORIES ${GEOGRAPHICLIB_INCLUDE_DIR})
endif()
find_package(SQLite3 REQUIRED)
# JSON (OpenMVG's sfm_data.json): a real parser, not a pattern scan (nlohmann-json3-dev, header-only)
find_package(nlohmann_json 3.2 REQUIRED)
find_package(Threads REQUIRED)
# JPEG 2000 of NITF images (IC = C8/M8) through OpenJPEG (libopenjp2-7-dev). Found by header and library:
# Debian's OpenJPEGConfig.cmake also imports the JPIP tools, which another package ships.
if(NOT TARGET tpkit_openjp2)
  find_path(OPENJP2_INCLUDE_DIR openjpeg.h PATH_SUFFIXES openjpeg-2.5 openjpeg-2.4 openjpeg-2.3 REQUIRED)
  find_library(OPENJP2_LIBRARY NAMES openjp2 REQUIRED)
  add_library(tpkit_openjp2 UNKNOWN IMPORTED)
  set_target_properties(tpkit_openjp2 PROPERTIES
    IMPORTED_LOCATION ${OPENJP2_LIBRARY} INTERFACE_INCLUDE_DIRECTORIES ${OPENJP2_INCLUDE_DIR})
endif()
# Coordinate reference systems and vertical datums of reference DEMs and GCPs (the ground component):
# PROJ (libproj-dev; geoid grids such as EGM96 from proj-data) and the GeoTIFF keys that name a DEM's CRS
# (libgeotiff-dev, found by header and library: Debian ships no CMake config for it).
find_package(PROJ CONFIG REQUIRED)
if(NOT TARGET tpkit_geotiff)
  find_path(GEOTIFF_INCLUDE_DIR geotiff.h PATH_SUFFIXES geotiff REQUIRED)
  find_library(GEOTIFF_LIBRARY NAMES geotiff REQUIRED)
  add_library(tpkit_geotiff UNKNOWN IMPORTED)
  set_target_properties(tpkit_geotiff PROPERTIES
    IMPORTED_LOCATION ${GEOTIFF_LIBRARY} INTERFACE_INCLUDE_DIRECTORIES ${GEOTIFF_INCLUDE_DIR})
endif()
# JPEG pictures inline in tp-report's page (libjpeg-dev, libjpeg-turbo): OpenCV's imgcodecs would bring
# GDAL and some 140 libraries into the tool.
find_package(JPEG REQUIRED)
# zlib (zlib1g-dev, libtiff's own): orthos' GeoTIFF tiles are deflated by the thread that made them (ortho
# component), only their writing serialized. OpenCV's video module above: the ECC alignment of orthos.
find_package(ZLIB REQUIRED)
