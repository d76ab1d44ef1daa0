# ctest driver: install the build tree into a temporary prefix, configure and build PROJECT_DIR
# against it as a user's project would (find_package(gausstrack)), then run RUN: a command line
# where @BUILD@ stands for that project's build directory and @PREFIX@ for the install prefix.
set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${WORK_DIR}")
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install "${PROJECT_BINARY_DIR}" --prefix "${prefix}")
run(${CMAKE_COMMAND} -S "${PROJECT_DIR}" -B "${WORK_DIR}/build" "-DCMAKE_PREFIX_PATH=${prefix}"
    -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build "${WORK_DIR}/build")
string(REPLACE "@BUILD@" "${WORK_DIR}/build" command "${RUN}")
string(REPLACE "@PREFIX@" "${prefix}" command "${command}")
separate_arguments(command)
run(${command})
