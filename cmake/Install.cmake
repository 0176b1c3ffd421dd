# What `cmake --install build [--prefix P]` and the Debian package (cpack -G DEB) install:
#   bin/                       the tools
#   share/man/man1, man5, man7 their pages (man tp-match, man tpkit-formats, man tpkit), uncompressed
#                              (man reads both; the package stays byte-identical to the sources)
#   share/tpkit/               the paper's clusters and the other data the README, docs/ and Makefile.examples use
#   include/tpkit/<component>/ the public headers; lib/ the static component libraries;
#   lib/cmake/tpkit/           tpkitConfig.cmake: find_package(tpkit) then link tpkit::tpkit (or one
#                              component, tpkit::match ...); lib/pkgconfig/tpkit.pc for pkg-config
# Tests and benchmarks are not installed.
include(CMakePackageConfigHelpers)

install(DIRECTORY ${PROJECT_SOURCE_DIR}/man/ DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 FILES_MATCHING PATTERN "*.1")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/man/ DESTINATION ${CMAKE_INSTALL_MANDIR}/man5 FILES_MATCHING PATTERN "*.5")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/man/ DESTINATION ${CMAKE_INSTALL_MANDIR}/man7 FILES_MATCHING PATTERN "*.7")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/share/tpkit/ DESTINATION ${CMAKE_INSTALL_DATADIR}/tpkit)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/lib/include/tpkit DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

get_property(tpkit_components GLOBAL PROPERTY TPKIT_COMPONENTS)
install(TARGETS ${tpkit_components} EXPORT tpkitTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
set(tpkit_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/tpkit)
install(EXPORT tpkitTargets NAMESPACE tpkit:: DESTINATION ${tpkit_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/tpkitConfig.cmake.in ${CMAKE_BINARY_DIR}/tpkitConfig.cmake
  INSTALL_DESTINATION ${tpkit_cmake_dir})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/tpkitConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/tpkitConfig.cmake ${CMAKE_BINARY_DIR}/tpkitConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/tpkitPublicDependencies.cmake DESTINATION ${tpkit_cmake_dir})
# the prefix relative to the .pc file, so that the file is right wherever the tree is installed
file(RELATIVE_PATH tpkit_pc_prefix ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig ${CMAKE_INSTALL_PREFIX})
configure_file(${PROJECT_SOURCE_DIR}/cmake/tpkit.pc.in ${CMAKE_BINARY_DIR}/tpkit.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/tpkit.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The Debian package: its runtime dependencies from the tools' shared libraries (dpkg-shlibdeps)
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME tpkit)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "tpkit developers <tpkit@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "tie points, three-view geometry and RPC models for satellite imagery")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "Command-line tools (tp-match, tp-chain, trifocal-fit, reproj-eval,\ncluster-homog, rpc-adjust, tp-ground, tp-convert, tp-plan, ...) that exchange plain-text files,\ntheir man pages, and the static libraries with headers, CMake and pkg-config files.")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/package)
include(CPack)
