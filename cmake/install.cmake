# `cmake --install build [--prefix P]`: the command, libgransim (shared and
# static), the public headers, gransim.pc, the man page, bash completion and
# the Python package, in the GNUInstallDirs layout under the prefix.
install(TARGETS gransim_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS gransim gransim_shared
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY include/gransim DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  FILES_MATCHING PATTERN "*.h")

# pkg-config: the shared library names its own dependencies; a static link
# needs them all (Requires.private for those with a .pc file, Libs.private for
# SUNDIALS, whose Debian package has none, OpenMP and libm).
# (hypre, Debian's built with MPI, is always linked: so is MPI)
set(GRANSIM_PC_REQUIRES_PRIVATE "yaml-0.1 gsl hdf5-serial nlopt fftw3 zlib lapack mpi-c")
set(GRANSIM_PC_LIBS_PRIVATE "")
foreach(lib ${HYPRE_LIB} ${CVODE_LIB} ${NVECSERIAL_LIB} ${SUNLINSOLSPGMR_LIB} ${SUNMATDENSE_LIB})
  get_filename_component(dir ${lib} DIRECTORY)
  get_filename_component(name ${lib} NAME_WE)
  string(REGEX REPLACE "^lib" "" name ${name})
  if(NOT dir IN_LIST GRANSIM_PC_SUNDIALS_DIRS AND NOT dir MATCHES "^/usr/lib(/${CMAKE_LIBRARY_ARCHITECTURE})?$")
    list(APPEND GRANSIM_PC_SUNDIALS_DIRS ${dir})
    string(APPEND GRANSIM_PC_LIBS_PRIVATE " -L${dir}")
  endif()
  string(APPEND GRANSIM_PC_LIBS_PRIVATE " -l${name}")
endforeach()
string(APPEND GRANSIM_PC_LIBS_PRIVATE " ${OpenMP_C_FLAGS} -lm")
file(RELATIVE_PATH GRANSIM_PC_TO_PREFIX /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" GRANSIM_PC_TO_PREFIX "${GRANSIM_PC_TO_PREFIX}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/gransim.pc.in ${CMAKE_CURRENT_BINARY_DIR}/gransim.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/gransim.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

install(FILES ${PROJECT_SOURCE_DIR}/docs/gransim.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(FILES ${PROJECT_SOURCE_DIR}/scripts/gransim-completion.bash
  DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME gransim)
install(FILES LICENSE CHANGELOG.md README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

# The Python package: under the prefix's dist-packages of Debian's python3
# (lib/python3.X/dist-packages, on sys.path for /usr/local), with _paths.py
# giving the library's path relative to the package.
find_program(GRANSIM_PYTHON python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT GRANSIM_PYTHON)
  find_program(GRANSIM_PYTHON python3)
endif()
set(GRANSIM_PYTHON_VERSION 3)
if(GRANSIM_PYTHON)
  execute_process(COMMAND ${GRANSIM_PYTHON} -c "import sys; print('%d.%d' % sys.version_info[:2])"
                  OUTPUT_VARIABLE GRANSIM_PYTHON_VERSION OUTPUT_STRIP_TRAILING_WHITESPACE)
endif()
set(GRANSIM_PYTHON_INSTALL_DIR lib/python${GRANSIM_PYTHON_VERSION}/dist-packages CACHE STRING
    "where cmake --install puts the Python package gransim, relative to the prefix")
file(RELATIVE_PATH GRANSIM_PY_TO_LIB /${GRANSIM_PYTHON_INSTALL_DIR}/gransim
     /${CMAKE_INSTALL_LIBDIR}/libgransim.so.${PROJECT_VERSION_MAJOR})
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/python_paths.py
     "# written by cmake --install: libgransim relative to this package\nLIBRARY = \"${GRANSIM_PY_TO_LIB}\"\n")
install(DIRECTORY python/gransim DESTINATION ${GRANSIM_PYTHON_INSTALL_DIR}
  FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/python_paths.py DESTINATION ${GRANSIM_PYTHON_INSTALL_DIR}/gransim
  RENAME _paths.py)
install(FILES python/examples/sweep_psd.py DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples/python)
