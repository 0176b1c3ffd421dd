# Every dependency is a Debian package (see scripts/install-deps.sh for the list).
include(${CMAKE_CURRENT_LIST_DIR}/tpkitPublicDependencies.cmake)
if(TPKIT_TESTS)
  find_package(GTest REQUIRED)
endif()
if(TPKIT_BENCH)
  find_package(benchmark REQUIRED)
endif()
