# Helpers that keep the build declarative: a component library is every .cpp in lib/src/<component>/,
# a tool is tools/<name>.cpp plus its man page man/<name>.1 (embedded as --help), a unit test is one
# file in tests/unit/<component>/, a tool test is tests/tools/<tool>.cmake, a benchmark is bench/<name>.cpp.

function(tpkit_component name)
  cmake_parse_arguments(C "" "" "DEPS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/lib/src/${name}/*.cpp)
  if(NOT srcs)
    add_library(tpkit_${name} INTERFACE)
    target_include_directories(tpkit_${name} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/lib/include>
                                                       $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_link_libraries(tpkit_${name} INTERFACE ${C_DEPS})
    set_target_properties(tpkit_${name} PROPERTIES EXPORT_NAME ${name})
    set_property(GLOBAL APPEND PROPERTY TPKIT_COMPONENTS tpkit_${name})
    return()
  endif()
  add_library(tpkit_${name} STATIC ${srcs})
  target_include_directories(tpkit_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/lib/include>
                                                  $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(tpkit_${name} PUBLIC ${C_DEPS})
  set_target_properties(tpkit_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY TPKIT_COMPONENTS tpkit_${name})
endfunction()

# The man page is the single source of the tool's words: it is embedded in the executable and
# rendered as plain text for --help (lib/src/core/tool_support.cpp).
function(tpkit_embed_man tool out_var)
  set(page ${PROJECT_SOURCE_DIR}/man/${tool}.1)
  if(EXISTS ${page})
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${page})
    file(READ ${page} text)
  else()
    # the tool still builds, but its test tool.${tool}.help fails until the page exists
    message(WARNING "tools/${tool}.cpp has no man page man/${tool}.1")
    set(text "")
  endif()
  string(MAKE_C_IDENTIFIER ${tool} ident)
  set(gen ${CMAKE_BINARY_DIR}/generated/man_${ident}.cpp)
  file(WRITE ${gen}.tmp "// Generated from man/${tool}.1 by cmake/TpkitHelpers.cmake; do not edit.\n"
    "extern const char* const tpkit_man_page;\n"
    "const char* const tpkit_man_page = R\"tpkitman(${text})tpkitman\";\n")
  file(COPY_FILE ${gen}.tmp ${gen} ONLY_IF_DIFFERENT)
  set(${out_var} ${gen} PARENT_SCOPE)
endfunction()

function(tpkit_tool name)
  cmake_parse_arguments(T "" "" "LIBS" ${ARGN})
  if(NOT EXISTS ${PROJECT_SOURCE_DIR}/tools/${name}.cpp)
    return()
  endif()
  tpkit_embed_man(${name} man_src)
  add_executable(${name} ${PROJECT_SOURCE_DIR}/tools/${name}.cpp ${man_src})
  target_link_libraries(${name} PRIVATE ${T_LIBS} tpkit_core)
  set_property(GLOBAL APPEND PROPERTY TPKIT_TOOLS ${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()
