# Sanitizer builds: -DHSLAM_SANITIZE=address,undefined (AddressSanitizer + UndefinedBehaviorSanitizer) or
# -DHSLAM_SANITIZE=thread (ThreadSanitizer). Empty (the default) builds without sanitizers.
# Fuzzing build: -DHSLAM_FUZZ=ON with clang (-DCMAKE_CXX_COMPILER=clang++): libFuzzer targets of test/fuzz, with
# everything compiled for coverage-guided fuzzing under AddressSanitizer + UBSan.
#
# Every target of the project (library, tutorials, tests) is instrumented; the system libraries (ViSP, OpenCV,
# Ceres) are not, which AddressSanitizer and UBSan tolerate. Any report stops the program (-fno-sanitize-recover
# for UBSan; ASan stops on its first report by default), so a test with a report fails. cmake/run.sh test runs the
# ASan+UBSan suite after the normal one and the ThreadSanitizer pass on the real-time (threaded) tests.
set(HSLAM_SANITIZE "" CACHE STRING "Sanitizers to build with: empty, address,undefined or thread")
option(HSLAM_SANITIZE_TEST_PROGRAMS "With HSLAM_SANITIZE: instrument the test programs' own code too (OFF: only the
library and the tutorials, the code users run; the test programs still link the sanitizer runtimes)" ON)

if(HSLAM_SANITIZE)
  string(REPLACE "," ";" _hslam_sanitizers "${HSLAM_SANITIZE}")
  foreach(_s ${_hslam_sanitizers})
    if(NOT _s MATCHES "^(address|undefined|thread)$")
      message(FATAL_ERROR "HSLAM_SANITIZE: unknown sanitizer '${_s}' (address, undefined or thread)")
    endif()
  endforeach()
  if("thread" IN_LIST _hslam_sanitizers AND "address" IN_LIST _hslam_sanitizers)
    message(FATAL_ERROR "HSLAM_SANITIZE: thread and address cannot be combined")
  endif()
  set(_hslam_flags "-fsanitize=${HSLAM_SANITIZE}" -fno-omit-frame-pointer -g1)
  if("undefined" IN_LIST _hslam_sanitizers)
    # Every UBSan check stops the program, except nonnull-attribute: it stays recoverable only so that its one
    # suppression (ViSP's vpImage copy, see cmake/sanitizers/ubsan.supp) can apply; UBSAN_OPTIONS=halt_on_error=1
    # still stops on any report that is not suppressed.
    list(APPEND _hslam_flags -fno-sanitize-recover=all -fsanitize-recover=nonnull-attribute)
    # Four of GCC's UBSan checks are left to AddressSanitizer and to the fuzz build: null (a null dereference is a
    # SEGV that ASan reports with its stack), object-size (ASan's red zones catch the overflows it looks for),
    # alignment and pointer-overflow (misaligned or wrapped pointers in binary parsing: the fuzz targets keep every
    # UBSan check, clang's full set). They put a check on every Eigen element access: measured on CoarseTracker.cpp
    # (2 GHz Zen 1), compile 60 -> 25 s; a relocalisation test 65 -> 48 s (the tracker's helpers inline again).
    list(APPEND _hslam_flags -fno-sanitize=alignment,null,object-size,pointer-overflow)
  endif()
  # GCC 12's flow analysis is confused by the sanitizer instrumentation: it reports -Wmaybe-uninitialized inside
  # libstdc++'s <regex> (std::function copies in regex_automaton.h) that the plain build does not; the plain build
  # keeps the warning.
  list(APPEND _hslam_flags -Wno-maybe-uninitialized)
  if("thread" IN_LIST _hslam_sanitizers)
    # GCC warns that TSan does not model std::atomic_thread_fence (-Wtsan). The one fence (FramePreprocessor's frame
    # pool) only strengthens the ordering of the shared_ptr count it follows; a synchronisation TSan missed would
    # show as a false race report, which the pass would fail on.
    list(APPEND _hslam_flags -Wno-tsan)
    # Eigen's SSE packets are 16-byte accesses, which TSan checks on its slow range path: half of the time of the
    # real-time tracking tests went there (the tracker's 9x9 normal equations). Scalar code is checked the same, at
    # the fast path: CoarseTracker-heavy tests run 1.8x faster (SystemSynthetic.RealTimeHybridCoveredLens 306 ->
    # 166 s on a 2 GHz Zen 1 core). The alignment stays at 16 bytes, the ABI of the uninstrumented Ceres.
    list(APPEND _hslam_flags -DEIGEN_DONT_VECTORIZE -DEIGEN_MAX_ALIGN_BYTES=16 -DEIGEN_MAX_STATIC_ALIGN_BYTES=16)
  endif()
  if("thread" IN_LIST _hslam_sanitizers AND NOT HSLAM_SANITIZE_TEST_PROGRAMS)
    # A synchronisation in uninstrumented code (an atomic in a test program) is invisible to TSan: false reports.
    message(FATAL_ERROR "HSLAM_SANITIZE=thread needs HSLAM_SANITIZE_TEST_PROGRAMS=ON: ThreadSanitizer must see all code")
  endif()
  if("address" IN_LIST _hslam_sanitizers)
    # Eigen turns its "malloc is already 16-byte aligned" shortcut off under AddressSanitizer (__SANITIZE_ADDRESS__)
    # and over-allocates by 16 bytes instead: an Eigen object allocated by instrumented code and freed by code that is
    # not (the test programs with HSLAM_SANITIZE_TEST_PROGRAMS=OFF, Ceres) is then a bad free. ASan's malloc is
    # 16-byte aligned on 64-bit glibc like glibc's own (and UBSan's alignment check would report it otherwise), so
    # every side uses plain malloc; ASan also sees an underflow the 16 spare bytes would hide.
    list(APPEND _hslam_flags -DEIGEN_MALLOC_ALREADY_ALIGNED=1)
  endif()
  # -O2 (it comes after Release's -O3 and wins): instrumented, -O3 compiled 12-20 % slower on the files measured
  # (CoarseTracker 48 -> 43 s, test_conversions 36 -> 28 s on a 2 GHz Zen 1 core) for no gain a sanitizer pass needs.
  list(APPEND _hslam_flags -O2)
  add_compile_options(${_hslam_flags})
  set(HSLAM_SANITIZE_COMPILE_OPTIONS ${_hslam_flags}) # taken off again by test/CMakeLists.txt when asked
  add_link_options("-fsanitize=${HSLAM_SANITIZE}")
  message(STATUS "HSLAM_SANITIZE: building with -fsanitize=${HSLAM_SANITIZE}")
endif()

option(HSLAM_FUZZ "Build the libFuzzer targets of test/fuzz (clang only; everything built with ASan + UBSan)" OFF)
if(HSLAM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "HSLAM_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  if(HSLAM_SANITIZE)
    message(FATAL_ERROR "HSLAM_FUZZ brings its own sanitizers: leave HSLAM_SANITIZE empty")
  endif()
  # -O1: the fuzz targets exercise parsers, whose speed does not matter (test/fuzz/CMakeLists.txt compiles only the
  # module's files they run).
  add_compile_options(-O1 -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fsanitize-recover=nonnull-attribute -fno-omit-frame-pointer -g1)
  add_link_options(-fsanitize=address,undefined)
endif()
