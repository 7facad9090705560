# cmake -P script: install, configure the consumer against the prefix, build, run.
# With -DPYTHON (the Python module was built), the installed package imports too.
file(REMOVE_RECURSE "${PREFIX}" "${CONSUMER_BUILD}")
function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${step} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${step}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
run("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}")
if(NOT EXISTS "${PREFIX}/lib/cmake/fgcal/fgcalConfig.cmake")
  message(FATAL_ERROR "installed tree has no lib/cmake/fgcal/fgcalConfig.cmake")
endif()
include("${CMAKE_CURRENT_LIST_DIR}/check_python_package.cmake")
check_python_package("${PREFIX}/${PYTHON_SITE}")
run("configure consumer" ${CMAKE_COMMAND} -S "${CONSUMER_SOURCE}" -B "${CONSUMER_BUILD}" -G "${GENERATOR}"
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${PREFIX}
    "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}"
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
run("build consumer" ${CMAKE_COMMAND} --build "${CONSUMER_BUILD}")
# The package compiles its consumer for the CPU the library was built for
# (FGCAL_ARCH): the same Eigen alignment on both sides of the headers. A
# package built without FGCAL_ARCH adds no -march of its own.
file(READ "${CONSUMER_BUILD}/compile_commands.json" consumer_commands)
string(REGEX MATCH "[^\n]*/main\\.cpp\\.o [^\n]*" main_command "${consumer_commands}")
if(NOT main_command)
  message(FATAL_ERROR "no compile command of the consumer's main.cpp in ${CONSUMER_BUILD}/compile_commands.json")
endif()
if(ARCH)
  string(FIND "${main_command}" "-march=${ARCH}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the package was built with FGCAL_ARCH=${ARCH} but compiles its consumer without "
                        "-march=${ARCH}:\n${main_command}")
  endif()
  message(STATUS "the consumer is compiled with -march=${ARCH}, as the library")
elseif(main_command MATCHES "-march=" AND NOT CONSUMER_FLAGS MATCHES "-march=")
  message(FATAL_ERROR "a package built without FGCAL_ARCH gave its consumer a -march:\n${main_command}")
endif()
run("run consumer" "${CONSUMER_BUILD}/consumer")
message(STATUS "consumer said:\n${last_output}")
if(NOT last_output MATCHES "converged")
  message(FATAL_ERROR "consumer did not report convergence")
endif()
# Without FGCAL_ARCH the library is compiled for baseline x86-64, with Eigen's
# 16-byte alignment, and the package pins that alignment on its consumers: a
# consumer compiled for AVX (e.g. -march=native) would otherwise align a Mat6
# to 32 bytes and lay out the library's structures differently from it. Such
# a consumer is built and run too, where this CPU can run it.
if(NOT ARCH)
  run("run consumer_alignment" "${CONSUMER_BUILD}/consumer_alignment")
  if(NOT last_output MATCHES "eigen alignment 16 ")
    message(FATAL_ERROR "the consumer compiles fgcal's headers with another Eigen alignment than the library's "
                        "16 bytes: ${last_output}")
  endif()
  file(READ "/proc/cpuinfo" cpuinfo)
  if(cpuinfo MATCHES "[ \t]avx2[ \n]" AND cpuinfo MATCHES "[ \t]fma[ \n]")
    set(avx_build "${CONSUMER_BUILD}-avx2")
    file(REMOVE_RECURSE "${avx_build}")
    run("configure an AVX2 consumer" ${CMAKE_COMMAND} -S "${CONSUMER_SOURCE}" -B "${avx_build}" -G "${GENERATOR}"
        -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${PREFIX}
        "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS} -march=x86-64-v3" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}")
    run("build the AVX2 consumer" ${CMAKE_COMMAND} --build "${avx_build}" --target consumer consumer_alignment)
    run("run the AVX2 consumer_alignment" "${avx_build}/consumer_alignment")
    if(NOT last_output MATCHES "eigen alignment 16 ")
      message(FATAL_ERROR "a consumer compiled with -march=x86-64-v3 aligns Eigen's types otherwise than the "
                          "library (16 bytes): ${last_output}")
    endif()
    run("run the AVX2 consumer" "${avx_build}/consumer")
    if(NOT last_output MATCHES "converged")
      message(FATAL_ERROR "the consumer compiled with -march=x86-64-v3 did not report convergence:\n${last_output}")
    endif()
    message(STATUS "a consumer compiled with -march=x86-64-v3 keeps the library's alignment and converges")
  else()
    message(STATUS "this CPU has no AVX2 and FMA: the AVX2 consumer is not built")
  endif()
endif()
# The kinematics and vision side, when the package has them (consumer/CMakeLists.txt).
if(EXISTS "${CONSUMER_BUILD}/consumer_modules")
  run("run consumer_modules" "${CONSUMER_BUILD}/consumer_modules")
  message(STATUS "consumer_modules said:\n${last_output}")
  if(NOT last_output MATCHES "modules ok")
    message(FATAL_ERROR "consumer_modules did not report success")
  endif()
endif()

# Only the user's API is installed: no linear-algebra machinery, no internal
# or detail folder, no detail:: helpers in the headers. One exception:
# CharucoDetector's private members point to two OpenCV-backed types that its
# header only forward-declares in fgcal::vision::detail, so that the header
# needs no aruco include; nothing there can be called.
foreach(internal linear_system schur_solver sparse_cholesky sparse_matrix)
  if(EXISTS "${PREFIX}/include/fgcal/core/${internal}.hpp")
    message(FATAL_ERROR "the internal header fgcal/core/${internal}.hpp was installed")
  endif()
endforeach()
file(GLOB_RECURSE installed_headers "${PREFIX}/include/fgcal/core/*" "${PREFIX}/include/fgcal/factors/*"
     "${PREFIX}/include/fgcal/kinematics/*" "${PREFIX}/include/fgcal/vision/*")
foreach(h ${installed_headers})
  if(h MATCHES "/(internal|detail)/")
    message(FATAL_ERROR "an internal header was installed: ${h}")
  endif()
  file(STRINGS "${h}" detail_lines REGEX "detail::|namespace detail")
  if(h MATCHES "/fgcal/vision/charuco_detector\\.hpp$")
    list(FILTER detail_lines EXCLUDE REGEX "^namespace detail {$|detail::(ArucoBoard|MarkerSet)[^A-Za-z0-9_]")
    file(STRINGS "${h}" detail_types REGEX "^struct (ArucoBoard|MarkerSet);$")
    list(LENGTH detail_types n_types)
    if(NOT n_types EQUAL 2)
      message(FATAL_ERROR "${h}: fgcal::vision::detail should hold only the declarations of ArucoBoard and MarkerSet")
    endif()
  endif()
  if(detail_lines)
    message(FATAL_ERROR "${h} exports detail:: helpers: ${detail_lines}")
  endif()
endforeach()
# The README's embedding example is this consumer's main.cpp, whole.
file(READ "${CONSUMER_SOURCE}/main.cpp" consumer_main)
file(READ "${CONSUMER_SOURCE}/../../../README.md" readme)
string(FIND "${readme}" "${consumer_main}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "README.md's embedding section does not show test/install/consumer/main.cpp verbatim")
endif()
message(STATUS "installed headers: the user's API only; README shows the consumer")
