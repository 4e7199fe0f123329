# hapsyn_add_plugin(<name> SOURCES <src>... [LIBRARIES <lib>...]
#                   [OUTPUT_DIRECTORY <dir>] [INSTALL_DESTINATION <dir>] [NO_INSTALL] [DEFINITIONS <def>...])
#
# Builds the shared library hapsyn-<name>.so that the hapsyn registry loads by name (<name> must
# be the name the plugin registers with HAPSYN_*_PLUGIN). The options schema is derived from the
# plugin's option declarations in C++ (hapsyn/options.hpp), so a plugin file is self-contained.
# Works in the hapsyn tree and out of tree after find_package(hapsyn).
function(hapsyn_add_plugin name)
  cmake_parse_arguments(ARG "NO_INSTALL" "SCHEMA;OUTPUT_DIRECTORY;INSTALL_DESTINATION" "SOURCES;LIBRARIES;DEFINITIONS" ${ARGN})
  if(ARG_SCHEMA)
    message(FATAL_ERROR "hapsyn_add_plugin(${name}): SCHEMA is no longer used (plugin API 3): declare the "
      "options in C++ with a static declare() function (see hapsyn/options.hpp) and drop schema.json")
  endif()
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "hapsyn_add_plugin(${name}): SOURCES is required")
  endif()
  set(target hapsyn_plugin_${name})
  add_library(${target} MODULE ${ARG_SOURCES})
  # Listed for hapsyn's aggregate target hapsyn_plugins (every shipped plugin, no test).
  set_property(GLOBAL APPEND PROPERTY HAPSYN_PLUGIN_TARGETS ${target})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME "hapsyn-${name}" PREFIX ""
    CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  if(TARGET hapsyn::hapsyn)
    target_link_libraries(${target} PRIVATE hapsyn::hapsyn ${ARG_LIBRARIES})
  else()
    target_link_libraries(${target} PRIVATE hapsyn ${ARG_LIBRARIES})
  endif()
  if(DEFINED HAPSYN_WARNINGS)
    target_compile_options(${target} PRIVATE ${HAPSYN_WARNINGS})
  endif()
  if(ARG_OUTPUT_DIRECTORY)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${ARG_OUTPUT_DIRECTORY})
  elseif(DEFINED HAPSYN_PLUGIN_OUTPUT_DIR)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${HAPSYN_PLUGIN_OUTPUT_DIR})
  endif()
  if(ARG_DEFINITIONS)
    target_compile_definitions(${target} PRIVATE ${ARG_DEFINITIONS})
  endif()
  if(ARG_NO_INSTALL)
  elseif(ARG_INSTALL_DESTINATION)
    install(TARGETS ${target} LIBRARY DESTINATION ${ARG_INSTALL_DESTINATION})
  elseif(DEFINED HAPSYN_PLUGIN_INSTALL_DIR)
    install(TARGETS ${target} LIBRARY DESTINATION ${HAPSYN_PLUGIN_INSTALL_DIR})
  endif()
endfunction()

# hapsyn_add_test(<name> <sources>... [LIBRARIES <lib>...] [LABELS <label>...])
# A GoogleTest executable registered with CTest (in-tree only). Tests run with the build tree's
# bin/ directory and the repository root available as HAPSYN_BINARY_DIR / HAPSYN_SOURCE_DIR.
function(hapsyn_add_test name)
  cmake_parse_arguments(ARG "" "" "LIBRARIES;LABELS" ${ARGN})
  if(NOT TARGET hapsyn OR NOT TARGET GTest::gtest OR NOT COMMAND gtest_discover_tests)
    message(FATAL_ERROR "hapsyn_add_test(${name}): only available inside the hapsyn source tree "
      "with HAPSYN_BUILD_TESTS=ON; out of tree, use add_executable() and add_test() directly")
  endif()
  add_executable(${name} ${ARG_UNPARSED_ARGUMENTS})
  target_link_libraries(${name} PRIVATE hapsyn hapsyn_internal GTest::gtest GTest::gtest_main ${ARG_LIBRARIES})
  target_compile_options(${name} PRIVATE ${HAPSYN_WARNINGS})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    HAPSYN_SOURCE_DIR="${PROJECT_SOURCE_DIR}" HAPSYN_BINARY_DIR="${PROJECT_BINARY_DIR}"
    HAPSYN_PLUGIN_DIR="${HAPSYN_PLUGIN_OUTPUT_DIR}"
    HAPSYN_TEST_PLUGIN_DIR="${PROJECT_BINARY_DIR}/test-plugins")
  set(labels fast)
  if(ARG_LABELS)
    set(labels ${ARG_LABELS})
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${labels}" TIMEOUT 600)
endfunction()

# hapsyn_kernel_sources(<target> [CONTRACT] [TRAPPING_MATH] <source>...)
#
# Adds <source>... to <target> as kernel sources: files holding per-sample or block kernels
# (hapsyn/accel/lanes.hpp, multiversion.hpp), compiled with the floating-point flags those need.
# None changes a computed value; each lets the compiler emit vector code where it otherwise
# could not, or keeps it from fusing:
#   -fno-math-errno     std::sqrt is one instruction (sqrtsd / vsqrtpd), not a libm call per lane
#                       kept for errno; sqrt's results are the same, only errno is not set.
#   -fno-trapping-math  a selection may compute both of its sides, so lane loops with a
#                       condition vectorise; only floating-point exception flags differ.
#   -ftree-vectorize    the lane loops vectorise also in builds below -O3 (RelWithDebInfo, -O2);
#                       at -O3 (Release) it is the default.
#   -ffp-contract=off   no contraction of a * b + c into a fused multiply-add in the AVX2 and
#                       AVX-512 versions: a kernel rounds as the scalar path does, bit for bit
#                       (block and per-sample paths agree; results do not depend on the CPU).
# CONTRACT leaves contraction to the compiler (GCC's default for C++: fused in the versions with
# FMA), for kernels that are faster fused and whose results may differ in the last bits between
# CPUs (hapsyn/accel/multiversion.hpp). TRAPPING_MATH keeps the default -ftrapping-math, for
# kernels without lane loops that need it: -fno-trapping-math also lets GCC evaluate comparisons
# and conversions speculatively, which changes the machine code of branchy per-sample code (the
# five-bar's and haptic 6R's kept the code they were verified with). Works in the hapsyn tree and
# out of tree; call it in the directory that defines the sources (source file properties are
# directory-scoped).
function(hapsyn_kernel_sources target)
  cmake_parse_arguments(ARG "CONTRACT;TRAPPING_MATH" "" "" ${ARGN})
  if(NOT ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "hapsyn_kernel_sources(${target}): no source files given")
  endif()
  set(flags -fno-math-errno)
  if(NOT ARG_TRAPPING_MATH)
    list(APPEND flags -fno-trapping-math)
  endif()
  list(APPEND flags -ftree-vectorize)
  if(NOT ARG_CONTRACT)
    list(APPEND flags -ffp-contract=off)
  endif()
  target_sources(${target} PRIVATE ${ARG_UNPARSED_ARGUMENTS})
  set_property(SOURCE ${ARG_UNPARSED_ARGUMENTS} APPEND PROPERTY COMPILE_OPTIONS ${flags})
endfunction()
