# Installs the built project into a temporary prefix, then configures, builds and runs the consumer
# project in tests/consumer against it, and runs the installed `timeopt plan` with no arguments from
# an empty directory: it must find the shipped default map in the prefix (share/timeopt/maps). Invoked by ctest with -D TIMEOPT_BINARY_DIR, CONSUMER_SOURCE_DIR,
# WORK_DIR and BUILD_TYPE.
file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
set(build "${WORK_DIR}/build")

function(run_step)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "step failed (${rc}): ${ARGV}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

if(NOT BUILD_TYPE)
  set(BUILD_TYPE Release)
endif()
run_step(${CMAKE_COMMAND} --install "${TIMEOPT_BINARY_DIR}" --prefix "${prefix}" --config ${BUILD_TYPE})
run_step(${CMAKE_COMMAND} -S "${CONSUMER_SOURCE_DIR}" -B "${build}"
         -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=${BUILD_TYPE})
run_step(${CMAKE_COMMAND} --build "${build}" --config ${BUILD_TYPE})
run_step("${build}/consumer")
run_step("${build}/conic_only")
set(empty "${WORK_DIR}/empty")
file(MAKE_DIRECTORY "${empty}")
execute_process(COMMAND "${prefix}/bin/timeopt" plan WORKING_DIRECTORY "${empty}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "installed timeopt plan from an empty directory failed (${rc}):\n${out}\n${err}")
endif()
string(FIND "${out}" "\"map\": \"${prefix}/share/timeopt/maps/forest_20x20.bt\"" at)
if(at EQUAL -1)
  message(FATAL_ERROR "installed timeopt plan did not read the installed map:\n${out}")
endif()
if(NOT EXISTS "${empty}/results/plan.csv" OR NOT EXISTS "${empty}/results/plan.png")
  message(FATAL_ERROR "installed timeopt plan wrote no results/plan.csv and results/plan.png in ${empty}")
endif()

