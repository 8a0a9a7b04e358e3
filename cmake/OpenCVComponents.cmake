# OpenCV from Debian's per-module -dev packages (libopencv-core-dev,
# libopencv-imgproc-dev, libopencv-imgcodecs-dev, libopencv-calib3d-dev).
# Debian ships OpenCVConfig.cmake only in the meta package libopencv-dev, which
# drags in every module (VTK, Qt, DNN...): hundreds of MB a kiosk image and CI
# do not need. So we locate the four modules we use directly.
find_path(OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
set(OpenCV_LIBS)
foreach(module core imgproc imgcodecs calib3d)
  find_library(OPENCV_${module}_LIBRARY opencv_${module} REQUIRED)
  if(NOT TARGET opencv::${module})
    add_library(opencv::${module} SHARED IMPORTED)
    set_target_properties(opencv::${module} PROPERTIES
      IMPORTED_LOCATION ${OPENCV_${module}_LIBRARY}
      INTERFACE_INCLUDE_DIRECTORIES ${OPENCV_INCLUDE_DIR})
  endif()
  list(APPEND OpenCV_LIBS opencv::${module})
endforeach()
message(STATUS "OpenCV modules: ${OpenCV_LIBS} (headers in ${OPENCV_INCLUDE_DIR})")
