# Helpers that give every project target the same warnings and layout.
include_guard(GLOBAL)

# mrvs_target_warnings(<target>): -Wall -Wextra (-Werror) on our own code only.
function(mrvs_target_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                                           -Wnon-virtual-dtor -Wcast-align -Wnull-dereference)
  if(MRVS_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  # Uninitialised Eigen matrices show up as NaN in debug builds.
  target_compile_definitions(${target} PRIVATE $<$<CONFIG:Debug>:EIGEN_INITIALIZE_MATRICES_BY_NAN>)
endfunction()

# mrvs_add_library(<name> [SOURCES ...] [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates static library mrvs_<name>, alias mrvs::<name>, include dir <cur>/include.
function(mrvs_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  if(ARG_SOURCES)
    add_library(mrvs_${name} STATIC ${ARG_SOURCES})
    target_include_directories(mrvs_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(mrvs_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    mrvs_target_warnings(mrvs_${name})
    set_target_properties(mrvs_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON UNITY_BUILD ${MRVS_UNITY_BUILD})
  else()
    add_library(mrvs_${name} INTERFACE)
    target_include_directories(mrvs_${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(mrvs_${name} INTERFACE ${ARG_PUBLIC_DEPS})
  endif()
  add_library(mrvs::${name} ALIAS mrvs_${name})
endfunction()

# mrvs_add_executable(<name> SOURCES ... DEPS ...): a tool in build/bin/.
function(mrvs_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  mrvs_target_warnings(${name})
  set_target_properties(${name} PROPERTIES UNITY_BUILD ${MRVS_UNITY_BUILD})
  set_property(GLOBAL APPEND PROPERTY MRVS_EXECUTABLES ${name})
endfunction()

# mrvs_add_gtest(<name> SOURCES ... DEPS ... [LABELS label] [PROPERTIES key value ...]):
# one gtest binary whose tests are registered in CTest (PROPERTIES go to every test).
function(mrvs_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS;PROPERTIES" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gmock GTest::gtest_main)
  mrvs_target_warnings(${name})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  # gtest_discover_tests splits a label list into separate arguments, so give each test ONE
  # label "unit_<labels>": `ctest -L` takes a regex, so both -L unit and -L <label> select it.
  string(JOIN "_" label unit ${ARG_LABELS})
  gtest_discover_tests(${name} WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
                       PROPERTIES LABELS ${label} ${ARG_PROPERTIES} DISCOVERY_TIMEOUT 60)
endfunction()
