# Fails when a module includes a module it may not use (the graph of docs/layering.md), or reaches
# into another module's private files with "../<module>/...". Run as
#   cmake -DSOURCE_DIR=<repo> [-DINJECT=<module>:<header>] -P check_layering.cmake
# INJECT adds one include line to <module> before the check, so that a ctest can show that an
# upward include is caught (that test is expected to fail).

cmake_policy(VERSION 3.16)

# Each module and the modules it may include directly (itself always allowed).
set(allowed_core "")
set(allowed_curve core)
set(allowed_conic core)
set(allowed_trajectory core curve)
set(allowed_temporal core curve conic trajectory)
set(allowed_map core)
set(allowed_spatial core curve map)
set(allowed_sim core curve trajectory)
set(allowed_planner core curve conic trajectory temporal map spatial)
set(allowed_io core curve conic trajectory temporal map spatial sim planner)
set(allowed_viz core curve trajectory map)
set(modules core curve conic trajectory temporal map spatial sim planner io viz)

if(NOT SOURCE_DIR)
  message(FATAL_ERROR "check_layering: pass -DSOURCE_DIR=<repository>")
endif()

set(violations "")
set(checked 0)
function(check_line module file line)
  if(line MATCHES "#include[ \t]*[\"<]timeopt/([a-z_]+)/")
    set(target "${CMAKE_MATCH_1}")
    if(NOT target STREQUAL module AND NOT target IN_LIST allowed_${module})
      set(violations "${violations}\n  ${file}: ${module} includes ${target}: ${line}" PARENT_SCOPE)
    endif()
  elseif(line MATCHES "#include[ \t]*\"\\.\\./([a-z_]+)/")
    set(violations "${violations}\n  ${file}: reaches into ${CMAKE_MATCH_1}'s private files: ${line}"
        PARENT_SCOPE)
  endif()
endfunction()

foreach(module ${modules})
  if(NOT IS_DIRECTORY "${SOURCE_DIR}/src/${module}" AND NOT IS_DIRECTORY "${SOURCE_DIR}/include/timeopt/${module}")
    message(FATAL_ERROR "check_layering: module '${module}' has no folder (update the graph here and in docs/layering.md)")
  endif()
  file(GLOB files "${SOURCE_DIR}/src/${module}/*.cpp" "${SOURCE_DIR}/src/${module}/*.h"
       "${SOURCE_DIR}/include/timeopt/${module}/*.h")
  foreach(file ${files})
    math(EXPR checked "${checked} + 1")
    file(STRINGS "${file}" lines REGEX "^[ \t]*#include")
    file(RELATIVE_PATH rel "${SOURCE_DIR}" "${file}")
    foreach(line ${lines})
      check_line(${module} "${rel}" "${line}")
    endforeach()
  endforeach()
endforeach()

# Every folder of src/ and include/timeopt/ must be a known module (or the CLI, which may use all).
file(GLOB dirs LIST_DIRECTORIES true "${SOURCE_DIR}/src/*" "${SOURCE_DIR}/include/timeopt/*")
foreach(dir ${dirs})
  if(IS_DIRECTORY "${dir}")
    get_filename_component(name "${dir}" NAME)
    if(NOT name IN_LIST modules AND NOT name STREQUAL "cli")
      set(violations "${violations}\n  ${dir}: a module the layering graph does not know")
    endif()
  endif()
endforeach()

if(INJECT)
  string(REPLACE ":" ";" parts "${INJECT}")
  list(GET parts 0 module)
  list(GET parts 1 header)
  check_line(${module} "(injected)" "#include \"${header}\"")
endif()

if(violations)
  message(FATAL_ERROR "check_layering: includes against docs/layering.md:${violations}")
endif()
message(STATUS "check_layering: ${checked} files of ${modules} follow docs/layering.md")
