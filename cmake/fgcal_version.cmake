# cmake -P script, run at every build of the fgcal command (apps/CMakeLists.txt):
# writes OUTPUT, a header with the project version and the git commit the
# sources come from, so that `fgcal --version` names the exact build.
#   -DVERSION=0.1.0 -DSOURCE_DIR=... -DGIT_EXECUTABLE=... (may be empty) -DOUTPUT=...
# The commit is `git describe --always --dirty` of SOURCE_DIR when SOURCE_DIR is
# the top of a git work tree; empty when git is missing or the sources are not
# a clone (a release tarball, or a folder inside some other repository, whose
# commit would be the wrong one). configure_file rewrites OUTPUT only when its
# text changes, so a build without a new commit or edit recompiles nothing.
set(describe "")
if(GIT_EXECUTABLE AND EXISTS "${GIT_EXECUTABLE}")
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --show-toplevel
                  RESULT_VARIABLE rc OUTPUT_VARIABLE top ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(rc EQUAL 0)
    file(REAL_PATH "${top}" top_real)
    file(REAL_PATH "${SOURCE_DIR}" source_real)
    if(top_real STREQUAL source_real)
      execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" describe --always --dirty
                      RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
      if(rc EQUAL 0)
        set(describe "${out}")
      endif()
    endif()
  endif()
endif()
set(FGCAL_VERSION "${VERSION}")
set(FGCAL_GIT_DESCRIBE "${describe}")
configure_file("${CMAKE_CURRENT_LIST_DIR}/fgcal_version.hpp.in" "${OUTPUT}" @ONLY)
