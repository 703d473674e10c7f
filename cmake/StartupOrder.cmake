# Load time of OpenImageIO's closure: the order of the libraries in the dynamic loader's scope.
#
# Since issue 13's third pass the proctex binary does not link OpenImageIO at all: image/ loads it
# with dlopen in the module proctex_image_oiio.so, and this function orders that module's DT_NEEDED
# list (image/CMakeLists.txt). Measured on a 512^2 render to EXR (the module loaded): 364 -> 293 ms
# CPU with the order (docs/synth.md, "Start-up of the command"). The history below is the binary's.
#
# Debian's OpenImageIO pulls in ~250 shared libraries (OpenCV -> GDAL, FFmpeg, DCMTK, GDCM, OpenVDB,
# ...). Loading them cost ~0.15 s of CPU per run of the command, 70% of it in the loader's symbol
# lookup (perf: do_lookup_x): every relocation searches the global scope from its start until it
# reaches the defining object, and that scope lists the libraries breadth-first from the
# executable's DT_NEEDED entries. The libraries with the most relocations (C++ libraries binding
# their own exported symbols: OpenVDB 57k, Xerces 8.6k, GDAL 6.5k, ...) sat 30-220 objects deep:
# 155k lookups x 80 objects on average. Naming them first in our DT_NEEDED list (they are loaded
# anyway) moves them to the front of the scope: 12.5M -> 4.5M objects searched and the user CPU of
# `proctex --version` from ~155 ms to ~90 ms (docs/synth.md, "Start-up").
#
# The libraries are not new dependencies: only those in OpenImageIO's own `ldd` closure at configure
# time are named. The C/C++ runtime comes first so that the runtime's symbols keep binding to it;
# the remaining changes of binding are between identical copies of C++ inline functions and type
# information (vague linkage; checked with LD_DEBUG=bindings). libnetcdf defines its own strlcat:
# it is left in place and libbsd named before GDAL (which pulls netcdf in), so netcdf keeps binding
# libbsd's as before.
# The list: the objects most bound to, by `LD_DEBUG=bindings proctex --version` (Debian 12).
# -DPROCTEX_STARTUP_ORDER=OFF links as before.
option(PROCTEX_STARTUP_ORDER "Name the most-bound shared libraries first (faster start-up)" ON)

set(PROCTEX_STARTUP_ORDER_LIBS
    libstdc++.so libm.so libgcc_s.so libc.so libbsd.so
    libopenvdb.so libxerces-c libgdal.so libgeos.so libcrypto.so libproj.so libOpenImageIO.so libdcmdata.so
    libpoppler.so libgdcmMSFF.so libkmldom.so libsqlite3.so libopencv_core.so libglib-2.0.so libOpenEXR-3
    liblapack.so liblog4cplus libhdf5_serial.so libIex-3 libOpenColorIO.so libspatialite.so libfftw3f.so
    liboflog.so libsrt-gnutls.so libgnutls.so libgeos_c.so libOpenImageIO_Util.so libgio-2.0.so libnettle.so
    libdfalt.so libmbedcrypto.so librttopo.so libnss3.so libavutil.so libofstd.so)

function(proctex_startup_order target)
  if(NOT PROCTEX_STARTUP_ORDER OR NOT CMAKE_SYSTEM_NAME STREQUAL "Linux")
    return()
  endif()
  find_program(PROCTEX_LDD ldd)
  if(NOT PROCTEX_LDD OR NOT TARGET OpenImageIO::OpenImageIO)
    return()
  endif()
  get_target_property(oiio OpenImageIO::OpenImageIO LOCATION)
  if(NOT oiio OR NOT EXISTS "${oiio}")
    return()
  endif()
  execute_process(COMMAND ${PROCTEX_LDD} ${oiio} OUTPUT_VARIABLE closure RESULT_VARIABLE rc ERROR_QUIET)
  if(NOT rc EQUAL 0)
    return()
  endif()
  # "libfoo.so.1 => /lib/x86_64-linux-gnu/libfoo.so.1 (0x...)" -> the paths.
  string(REGEX MATCHALL "=> (/[^ ]+)" found "${closure}")
  set(paths "${oiio}")
  foreach(f IN LISTS found)
    string(REGEX REPLACE "^=> " "" f "${f}")
    list(APPEND paths "${f}")
  endforeach()
  set(ordered)
  foreach(prefix IN LISTS PROCTEX_STARTUP_ORDER_LIBS)
    foreach(p IN LISTS paths)
      get_filename_component(name "${p}" NAME)
      string(FIND "${name}" "${prefix}" at)
      if(at EQUAL 0)
        list(APPEND ordered "${p}")
        break()
      endif()
    endforeach()
  endforeach()
  list(REMOVE_DUPLICATES ordered)
  list(LENGTH ordered n)
  if(n GREATER 0)
    message(STATUS "proctex: ${n} shared libraries named first for a faster start-up (PROCTEX_STARTUP_ORDER)")
    target_link_options(${target} PRIVATE "LINKER:--push-state,--no-as-needed" ${ordered} "LINKER:--pop-state")
  endif()
endfunction()
