# The seeds of fuzz_sqlite_bag, made from the shared fixtures each time the
# target is built, into the build's working corpus (build-fuzz/corpus/
# fuzz_sqlite_bag/, which scripts/fuzz.sh passes first). Without the shared
# data the target starts from the tiny committed seeds alone.
if(EXISTS "${FGCAL_SHARED_DATA_DIR}/bags")
  add_executable(fuzz_sqlite_bag_seeds fuzz_sqlite_bag_seeds.cpp)
  target_link_libraries(fuzz_sqlite_bag_seeds PRIVATE sqlite3)
  target_compile_features(fuzz_sqlite_bag_seeds PRIVATE cxx_std_17)
  fgcal_set_warnings(fuzz_sqlite_bag_seeds)
  add_dependencies(fuzz_sqlite_bag fuzz_sqlite_bag_seeds)
  add_custom_command(TARGET fuzz_sqlite_bag POST_BUILD
    COMMAND fuzz_sqlite_bag_seeds "${FGCAL_SHARED_DATA_DIR}/bags" "${CMAKE_BINARY_DIR}/corpus/fuzz_sqlite_bag"
    COMMENT "fuzz_sqlite_bag: seeds from the shared rosbag2 fixtures")
endif()
