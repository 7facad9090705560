# cmake -P script: the module rules of docs/design.md, checked on the sources.
#   core      : Eigen and CHOLMOD only (no OpenCV, urdfdom, yaml-cpp, no other fgcal module)
#   kinematics: never vision/ or OpenCV
#   vision    : never kinematics/ or urdfdom
#   factors   : never apps/
#   apps/logs : nothing of ours, no OpenCV (the robot-log readers)
set(rules
  "core|opencv2/|urdf|yaml-cpp|fgcal/kinematics/|fgcal/vision/|fgcal/factors/|fgcal/apps/"
  "kinematics|opencv2/|fgcal/vision/|fgcal/apps/|fgcal/factors/"
  "vision|urdf|fgcal/kinematics/|fgcal/apps/|fgcal/factors/"
  "factors|fgcal/apps/"
  "apps/logs|opencv2/|fgcal/core/|fgcal/kinematics/|fgcal/vision/|fgcal/factors/|fgcal/apps/")
set(failures "")
foreach(rule ${rules})
  string(REPLACE "|" ";" parts "${rule}")
  list(POP_FRONT parts module)
  file(GLOB_RECURSE files "${SOURCE_DIR}/${module}/*.hpp" "${SOURCE_DIR}/${module}/*.cpp" "${SOURCE_DIR}/${module}/*.in")
  foreach(f ${files})
    file(STRINGS "${f}" includes REGEX "^[ \t]*#[ \t]*include")
    foreach(line ${includes})
      foreach(forbidden ${parts})
        string(FIND "${line}" "${forbidden}" pos)
        if(NOT pos EQUAL -1)
          string(APPEND failures "\n  ${f}: '${line}' (module ${module} may not include ${forbidden})")
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()
if(failures)
  message(FATAL_ERROR "module rules of docs/design.md broken:${failures}")
endif()
message(STATUS "module rules hold")
