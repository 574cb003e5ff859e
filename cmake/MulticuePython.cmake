# The Python interpreter and pybind11 for python/. Debian's pybind11-dev, python3-numpy and
# python3-pytest are made for the system interpreter; another python3 first on PATH (pyenv, a
# virtual environment) is used only when it can import NumPy. -DPython3_EXECUTABLE=... chooses.
# Sets MULTICUE_PYTHON_FOUND when both the interpreter (with its headers) and pybind11 are there.
set(MULTICUE_PYTHON_FOUND OFF)
if(NOT DEFINED Python3_EXECUTABLE)
  find_program(_multicue_path_python NAMES python3 NO_CACHE)
  set(_multicue_python_ok OFF)
  if(_multicue_path_python)
    execute_process(COMMAND ${_multicue_path_python} -c "import numpy"
                    RESULT_VARIABLE _rc OUTPUT_QUIET ERROR_QUIET)
    if(_rc EQUAL 0)
      set(_multicue_python_ok ON)
    endif()
  endif()
  if(NOT _multicue_python_ok AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH
        "Python interpreter of the bindings and their tests")
  endif()
endif()
find_package(Python3 COMPONENTS Interpreter Development.Module QUIET)
if(Python3_Development.Module_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)
  if(pybind11_FOUND)
    set(MULTICUE_PYTHON_FOUND ON)
  endif()
endif()
