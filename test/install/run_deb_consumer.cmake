# cmake -P script: build the Debian package with CPack in the build tree,
# unpack it into a scratch root (no root rights, nothing installed on the
# system), check its control fields and command, then configure, build and
# run the consumer project against <root>/usr.
#   -DBUILD_DIR -DWORK_DIR -DCPACK -DCONSUMER_SOURCE -DGENERATOR -DCONSUMER_FLAGS -DVERSION
#   -DLAUNCHER (the build's compiler launcher, e.g. ccache, reused to keep the test short)
#   -DPYTHON -DPYTHON_SITE -DPYTHON_ENV when the Python module was built: it imports from the unpacked tree
find_program(DPKG_DEB dpkg-deb)
if(NOT DPKG_DEB)
  message(STATUS "SKIPPED: dpkg-deb not found; the Debian package can only be checked on Debian and derivatives")
  return()
endif()
file(REMOVE_RECURSE "${WORK_DIR}")
set(root "${WORK_DIR}/root")
set(consumer_build "${WORK_DIR}/consumer-build")
function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${step} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${step}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run("cpack -G DEB" "${CPACK}" -G DEB --config "${BUILD_DIR}/CPackConfig.cmake" -B "${WORK_DIR}/packages")
file(GLOB debs "${WORK_DIR}/packages/*.deb")
list(LENGTH debs n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "expected one .deb in ${WORK_DIR}/packages, found ${n}: ${debs}")
endif()

# Control fields: name, the project version, and the -dev packages the
# installed CMake package needs.
run("read control fields" "${DPKG_DEB}" -f "${debs}" Package Version Depends)
set(fields "${last_output}")
message(STATUS "control fields:\n${fields}")
foreach(expected "Package: fgcal" "Version: ${VERSION}" "libeigen3-dev" "libsuitesparse-dev")
  string(FIND "${fields}" "${expected}" pos)
  if(pos EQUAL -1)
    message(FATAL_ERROR "the package's control fields lack '${expected}':\n${fields}")
  endif()
endforeach()

run("dpkg-deb -x" "${DPKG_DEB}" -x "${debs}" "${root}")
foreach(f usr/bin/fgcal usr/lib/cmake/fgcal/fgcalConfig.cmake usr/include/fgcal/core/optimizer.hpp)
  if(NOT EXISTS "${root}/${f}")
    message(FATAL_ERROR "the package has no /${f}")
  endif()
endforeach()
run("packaged fgcal --version" "${root}/usr/bin/fgcal" --version)
if(NOT last_output MATCHES "^fgcal ${VERSION}")
  message(FATAL_ERROR "packaged fgcal --version printed '${last_output}', expected 'fgcal ${VERSION}...'")
endif()
include("${CMAKE_CURRENT_LIST_DIR}/check_python_package.cmake")
check_python_package("${root}/usr/${PYTHON_SITE}")

run("configure consumer" ${CMAKE_COMMAND} -S "${CONSUMER_SOURCE}" -B "${consumer_build}" -G "${GENERATOR}"
    -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${root}/usr" "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}"
    "-DCMAKE_CXX_FLAGS=${CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${CONSUMER_FLAGS}")
# The package found must be the unpacked one, not an fgcal installed on the system.
file(STRINGS "${consumer_build}/CMakeCache.txt" found_dir REGEX "^fgcal_DIR:")
string(FIND "${found_dir}" "${root}/usr/" pos)
if(pos EQUAL -1)
  message(FATAL_ERROR "the consumer found fgcal elsewhere: ${found_dir}; expected under ${root}/usr")
endif()
run("build consumer" ${CMAKE_COMMAND} --build "${consumer_build}")
run("run consumer" "${consumer_build}/consumer")
message(STATUS "consumer said:\n${last_output}")
if(NOT last_output MATCHES "converged")
  message(FATAL_ERROR "consumer did not report convergence")
endif()
# The kinematics and vision side, when the package has them (consumer/CMakeLists.txt).
if(EXISTS "${consumer_build}/consumer_modules")
  run("run consumer_modules" "${consumer_build}/consumer_modules")
  message(STATUS "consumer_modules said:\n${last_output}")
  if(NOT last_output MATCHES "modules ok")
    message(FATAL_ERROR "consumer_modules did not report success")
  endif()
endif()
