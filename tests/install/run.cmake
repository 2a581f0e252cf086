# ctest Install.OutsideProjectFindsOdotune: installs the build tree BUILD_DIR
# into WORK_DIR/prefix, checks that the exported targets carry none of
# odotune's warning flags, then configures, builds and runs this folder's
# project against that prefix. Any failing step fails the test.
#   cmake -DBUILD_DIR=… -DWORK_DIR=… -DCXX=… [-DLAUNCHER=…] -P run.cmake
set(src ${CMAKE_CURRENT_LIST_DIR})
set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install test: ${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_out "${out}" PARENT_SCOPE)
endfunction()

step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f odotuneConfig.cmake odotuneConfigVersion.cmake odotuneTargets.cmake)
  if(NOT EXISTS ${prefix}/lib/cmake/odotune/${f})
    message(FATAL_ERROR "install test: ${prefix}/lib/cmake/odotune/${f} was not installed")
  endif()
endforeach()
file(GLOB _targets ${prefix}/lib/cmake/odotune/odotuneTargets*.cmake)
foreach(f ${_targets})
  file(READ ${f} text)
  if(text MATCHES "-Werror|-Wconversion")
    message(FATAL_ERROR "install test: ${f} passes odotune's warning flags on to consumers")
  endif()
endforeach()

# Every installed header includes odotune's others as <odotune/MODULE/…>,
# never as "MODULE/…", which would find a consumer's own folder first.
file(GLOB_RECURSE _headers ${prefix}/include/odotune/*.h)
list(LENGTH _headers _n)
if(_n EQUAL 0)
  message(FATAL_ERROR "install test: no headers under ${prefix}/include/odotune")
endif()
foreach(h ${_headers})
  file(STRINGS ${h} _bad REGEX "^[ \t]*#[ \t]*include[ \t]*\"[a-z_]+/")
  if(_bad)
    message(FATAL_ERROR "install test: ${h} includes ${_bad} without the odotune/ prefix")
  endif()
endforeach()

set(launcher "")
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
step("configuring the consumer" ${CMAKE_COMMAND} -S ${src} -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release
     -DCMAKE_CXX_COMPILER=${CXX} ${launcher} -DCMAKE_PREFIX_PATH=${prefix} -DEXPECTED_PREFIX=${prefix})
step("building the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
step("running the consumer" ${WORK_DIR}/build/consumer)
message("${step_out}")
