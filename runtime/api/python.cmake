# `import sdfc` (runtime/api/python/sdfc_python.cpp, pybind11 over libsdfc.so): built where
# pybind11 and Python's headers are found (Debian: pybind11-dev python3-dev; numpy at run
# time: python3-numpy; the tests: python3-pytest). Not under sanitizers (Python would need
# their runtimes preloaded).
if(SDFC_SANITIZE OR SDFC_TSAN OR SDFC_FUZZ)
  return()
endif()
# Debian's Python, whose numpy and pytest the packages give (not a pyenv or venv on PATH).
if(NOT DEFINED PYTHON_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(PYTHON_EXECUTABLE /usr/bin/python3)
endif()
find_package(pybind11 CONFIG QUIET)
if(NOT pybind11_FOUND)
  message(STATUS "pybind11 not found: no Python module (apt-get install pybind11-dev python3-dev)")
  return()
endif()
pybind11_add_module(sdfc_python MODULE runtime/api/python/sdfc_python.cpp)
target_link_libraries(sdfc_python PRIVATE sdfc_api)
target_include_directories(sdfc_python PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
set(SDFC_PYTHON_DIR lib/python3/dist-packages)  # Debian's place for a prefix's modules
file(RELATIVE_PATH SDFC_PYTHON_TO_LIB "${CMAKE_INSTALL_PREFIX}/${SDFC_PYTHON_DIR}" "${CMAKE_INSTALL_FULL_LIBDIR}")
set_target_properties(sdfc_python PROPERTIES OUTPUT_NAME sdfc LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/python
                      INSTALL_RPATH "$ORIGIN/${SDFC_PYTHON_TO_LIB}")
install(TARGETS sdfc_python LIBRARY DESTINATION ${SDFC_PYTHON_DIR})
set(SDFC_PYTHON ${PYTHON_EXECUTABLE} CACHE INTERNAL "the Python the module is built for")
