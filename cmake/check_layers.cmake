# The Layering test: every #include <odotune/MODULE/…> in a module's folder
# (odotune/MODULE/) names the module itself or one it uses (CMakeLists.txt, odotune_module USES, with
# what those use in turn). An upward include (tracks/ including cli/, say)
# fails the test with file:line and the modules that folder may use.
#
#   cmake -DROOT=<tree> -DLAYERS=<build>/layers.cmake -P check_layers.cmake
#
# LAYERS (written at configure time) sets ODOTUNE_MODULES and, for each
# module M, ODOTUNE_USES_M. Includes of anything that is not a module
# (<Eigen/Dense>, "support/…" in tests) are not checked; a module header
# included without the package name ("tracks/track.h") fails the test too.
cmake_minimum_required(VERSION 3.25)
if(NOT DEFINED ROOT OR NOT DEFINED LAYERS)
  message(FATAL_ERROR "usage: cmake -DROOT=<tree> -DLAYERS=<layers.cmake> -P check_layers.cmake")
endif()
include(${LAYERS})

set(violations 0)
set(checked 0)
foreach(m ${ODOTUNE_MODULES})
  file(GLOB files ${ROOT}/odotune/${m}/*.h ${ROOT}/odotune/${m}/*.cpp)
  foreach(f ${files})
    math(EXPR checked "${checked} + 1")
    file(STRINGS ${f} lines)
    set(n 0)
    foreach(line IN LISTS lines)
      math(EXPR n "${n} + 1")
      if(line MATCHES "^[ \t]*#[ \t]*include[ \t]*\"([a-z_]+)/" AND CMAKE_MATCH_1 IN_LIST ODOTUNE_MODULES)
        file(RELATIVE_PATH rel ${ROOT} ${f})
        message(SEND_ERROR "${rel}:${n}: includes \"${CMAKE_MATCH_1}/…\": module headers are included as "
                           "<odotune/${CMAKE_MATCH_1}/…>")
        math(EXPR violations "${violations} + 1")
      endif()
      if(line MATCHES "^[ \t]*#[ \t]*include[ \t]*[<\"]odotune/([a-z_]+)/")
        set(dep ${CMAKE_MATCH_1})
        if(NOT dep STREQUAL m AND dep IN_LIST ODOTUNE_MODULES AND NOT dep IN_LIST ODOTUNE_USES_${m})
          file(RELATIVE_PATH rel ${ROOT} ${f})
          message(SEND_ERROR "${rel}:${n}: module ${m} includes ${dep}/, which it does not use "
                             "(${m} uses: ${ODOTUNE_USES_${m}})")
          math(EXPR violations "${violations} + 1")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()
if(checked EQUAL 0)
  message(FATAL_ERROR "no module files found under ${ROOT}")
endif()
if(violations GREATER 0)
  message(FATAL_ERROR "${violations} include(s) against the layering in ${checked} files")
endif()
message(STATUS "layering: ${checked} files, every include points down")
