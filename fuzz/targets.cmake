# The fuzz targets and what each links; shared by fuzz/CMakeLists.txt (the
# libFuzzer build, clang) and test/fuzz/CMakeLists.txt (the regression runners
# of the normal build). Each target is fuzz/<name>.cpp with its seed corpus in
# fuzz/corpus/<name>/ and its crash inputs in fuzz/regressions/<name>/.
set(FGCAL_FUZZ_TARGETS)
set(fgcal_fuzz_io "")
if(TARGET fgcal::apps)
  set(fgcal_fuzz_io fgcal::apps)
elseif(FGCAL_BUILD_FUZZERS AND TARGET fgcal::kinematics)
  # The fuzz build (scripts/fuzz.sh) skips the apps module, whose solver,
  # simulator and report are not fuzzed: the readers of rig.yaml and
  # joints.csv are built alone, from the same sources.
  find_package(yaml-cpp REQUIRED)
  set(io ${PROJECT_SOURCE_DIR}/apps/src/io)
  add_library(fgcal_fuzz_io STATIC ${io}/rig_config.cpp ${io}/yaml_read.cpp ${io}/joints_csv.cpp
                                   ${io}/text_format.cpp ${io}/errors.cpp ${io}/atomic_write.cpp
                                   ${io}/urdf_update.cpp)
  target_include_directories(fgcal_fuzz_io PUBLIC ${PROJECT_SOURCE_DIR}/apps/include PRIVATE ${PROJECT_SOURCE_DIR}/apps/src)
  target_link_libraries(fgcal_fuzz_io PUBLIC fgcal::core fgcal::kinematics PRIVATE yaml-cpp)
  set(fgcal_fuzz_io fgcal_fuzz_io)
endif()
if(fgcal_fuzz_io)
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_rig_yaml fuzz_joints_csv fuzz_urdf_origin)
  set(FGCAL_FUZZ_LIBS_fuzz_rig_yaml ${fgcal_fuzz_io})
  set(FGCAL_FUZZ_LIBS_fuzz_urdf_origin ${fgcal_fuzz_io})
  set(FGCAL_FUZZ_LIBS_fuzz_joints_csv ${fgcal_fuzz_io})
endif()
if(TARGET fgcal::kinematics)
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_urdf)
  set(FGCAL_FUZZ_LIBS_fuzz_urdf fgcal::kinematics)
endif()
if(TARGET fgcal::logs)
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_ros1_bag)
  set(FGCAL_FUZZ_LIBS_fuzz_ros1_bag fgcal::logs)
endif()
if(TARGET fgcal::vision)
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_board_detect fuzz_image_header)
  set(FGCAL_FUZZ_LIBS_fuzz_board_detect fgcal::vision opencv_imgcodecs)
  set(FGCAL_FUZZ_LIBS_fuzz_image_header fgcal::vision opencv_imgcodecs)
endif()
if(TARGET fgcal::logs)
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_mcap fuzz_cdr)
  set(FGCAL_FUZZ_LIBS_fuzz_mcap fgcal::logs)
  set(FGCAL_FUZZ_LIBS_fuzz_cdr fgcal::logs)
  # rosbag2 sqlite3 files; its seeds are made at fuzz-build time
  # (fuzz_sqlite_bag_seeds.cmake, included by fuzz/CMakeLists.txt).
  list(APPEND FGCAL_FUZZ_TARGETS fuzz_sqlite_bag)
  set(FGCAL_FUZZ_LIBS_fuzz_sqlite_bag fgcal::logs)
endif()
