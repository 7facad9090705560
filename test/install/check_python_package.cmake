# Included by the install scripts: when the Python module was built (PYTHON
# set), the installed tree's package must import from where it was installed,
# say the project's version and compute with numpy.
#   PYTHON: the interpreter it was built for; PYTHON_ENV: NAME=VALUE items for
#   it (a sanitized build's runtimes), separated by '|'; VERSION: the project's version.
function(check_python_package site_dir)
  if(NOT PYTHON)
    return()
  endif()
  if(NOT EXISTS "${site_dir}/fgcal/__init__.py")
    message(FATAL_ERROR "the Python package is not installed: no ${site_dir}/fgcal/__init__.py")
  endif()
  file(GLOB extension "${site_dir}/fgcal/_fgcal*.so")
  if(NOT extension)
    message(FATAL_ERROR "the Python package has no extension module: no ${site_dir}/fgcal/_fgcal*.so")
  endif()
  string(REPLACE "|" ";" env "${PYTHON_ENV}")
  set(code "import fgcal, numpy; T = fgcal.se3.exp([0, 0, 0, 1, 2, 3]); print(fgcal.__version__, T[2, 3], fgcal.__file__)")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env "PYTHONPATH=${site_dir}" PYTHONDONTWRITEBYTECODE=1 ${env}
                          "${PYTHON}" -c "${code}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "importing the installed Python package failed (${rc}):\n${out}\n${err}")
  endif()
  if(NOT out STREQUAL "${VERSION} 3.0 ${site_dir}/fgcal/__init__.py")
    message(FATAL_ERROR "the installed Python package printed '${out}', expected '${VERSION} 3.0 "
                        "${site_dir}/fgcal/__init__.py'")
  endif()
  message(STATUS "Python package: ${out}")
endfunction()
