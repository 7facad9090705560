# Helpers shared by every module: warnings kept on our own targets only, and a
# one-call library definition with a fgcal:: alias, installed headers and export.

function(fgcal_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
endfunction()

# fgcal_add_module(NAME SOURCES ... PUBLIC_DEPS ... PRIVATE_DEPS ... [HEADERS ...])
# Defines library fgcal_<NAME> (alias fgcal::<NAME>, exported as fgcal::<NAME>)
# whose public headers live in <module>/include/fgcal/<NAME>/. HEADERS, when
# given, lists every one of them (paths under include/): exactly those are
# installed, and a header there that is not listed stops the configuration,
# so that nothing meant to stay inside the library is installed by accident.
# Without HEADERS the whole of include/fgcal is installed. SKIP_HEADERS lists
# headers that are present but left out on purpose (a part of the module that
# this configuration does not build), neither installed nor an error.
#
# A module with an <module>/internal/ folder (headers the library and its own
# tests share, never installed) gets it as a private include directory, and an
# INTERFACE target fgcal_<NAME>_internal (the library plus that folder) for
# the project's own tests, benchmarks and modules; it is not exported.
function(fgcal_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS;HEADERS;SKIP_HEADERS" ${ARGN})
  set(target fgcal_${name})
  add_library(${target} ${ARG_SOURCES})
  add_library(fgcal::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME fgcal_${name}
                        POSITION_INDEPENDENT_CODE ON)
  target_compile_features(${target} PUBLIC cxx_std_17)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  # The solver's kernels, the factors' fast paths among them, are compiled
  # here, with the library's flags, not in the user's translation units: the
  # target CPU is the library's to choose (FGCAL_ARCH). It is PUBLIC, so a
  # consumer of the package is compiled for the same CPU: Eigen's alignment of
  # fixed-size types (16 or 32 bytes) is part of the headers' ABI.
  # Without FGCAL_ARCH, Eigen's alignment is pinned at the baseline's 16
  # bytes on both sides instead: a consumer compiled with -march=native would
  # otherwise align a Mat6 member to 32 and lay out the library's public
  # structures differently from the library itself. So is the heap: such a
  # consumer would free a matrix that the library allocated with malloc (a
  # covariance returned by value) through Eigen's own aligned allocator and
  # crash, so both sides allocate as the library does (malloc on 64-bit glibc,
  # Eigen's allocator under AddressSanitizer, as Eigen itself decides there).
  if(FGCAL_ARCH)
    target_compile_options(${target} PUBLIC "-march=${FGCAL_ARCH}")
  else()
    target_compile_definitions(${target} PUBLIC EIGEN_MAX_ALIGN_BYTES=16)
    if(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND CMAKE_SIZEOF_VOID_P EQUAL 8)
      if(FGCAL_SANITIZE MATCHES "address")
        target_compile_definitions(${target} PUBLIC EIGEN_MALLOC_ALREADY_ALIGNED=0)
      else()
        target_compile_definitions(${target} PUBLIC EIGEN_MALLOC_ALREADY_ALIGNED=1)
      endif()
    endif()
  endif()
  fgcal_set_warnings(${target})
  install(TARGETS ${target} EXPORT fgcalTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  if(ARG_HEADERS)
    file(GLOB_RECURSE present RELATIVE "${CMAKE_CURRENT_SOURCE_DIR}/include" "${CMAKE_CURRENT_SOURCE_DIR}/include/*")
    foreach(h ${present})
      if(NOT h IN_LIST ARG_HEADERS AND NOT h IN_LIST ARG_SKIP_HEADERS)
        message(FATAL_ERROR "fgcal_add_module(${name}): include/${h} is not in HEADERS; a header the library "
                            "keeps to itself belongs in ${CMAKE_CURRENT_SOURCE_DIR}/internal")
      endif()
    endforeach()
    foreach(h ${ARG_HEADERS})
      get_filename_component(dir "${h}" DIRECTORY)
      install(FILES "include/${h}" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/${dir}")
    endforeach()
  else()
    install(DIRECTORY include/fgcal DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
  if(EXISTS "${CMAKE_CURRENT_SOURCE_DIR}/internal")
    target_include_directories(${target} PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/internal")
    add_library(${target}_internal INTERFACE)
    target_include_directories(${target}_internal INTERFACE "${CMAKE_CURRENT_SOURCE_DIR}/internal")
    target_link_libraries(${target}_internal INTERFACE ${target})
  endif()
endfunction()

# Adds each listed sub-folder that has a CMakeLists.txt, skipping the folder of
# a module that is switched off (kinematics, vision and apps are optional).
function(fgcal_add_module_folders)
  foreach(dir ${ARGN})
    if(dir MATCHES "^(kinematics|vision|apps)$" AND NOT TARGET fgcal::${dir})
      continue()
    endif()
    if(EXISTS "${CMAKE_CURRENT_SOURCE_DIR}/${dir}/CMakeLists.txt")
      add_subdirectory(${dir})
    endif()
  endforeach()
endfunction()
