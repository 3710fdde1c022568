# Resolves ATMO_ARCH to a -march flag. "auto" picks x86-64-v3 (AVX2, FMA: every x86 CPU since
# 2013) when the compiler accepts it and a probe compiled with it runs on this machine; the
# per-pixel and per-texel loops vectorise and use FMA with it. "none" adds nothing.
include(CheckCXXSourceRuns)

function(atmo_resolve_arch out_var)
  if(ATMO_ARCH STREQUAL "none" OR ATMO_ARCH STREQUAL "")
    set(${out_var} "" PARENT_SCOPE)
  elseif(ATMO_ARCH STREQUAL "auto")
    set(CMAKE_REQUIRED_FLAGS "-march=x86-64-v3")
    check_cxx_source_runs("
      int main() {
        __builtin_cpu_init();
        return (__builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\")) ? 0 : 1;
      }" ATMO_HOST_RUNS_X86_64_V3)
    unset(CMAKE_REQUIRED_FLAGS)
    if(ATMO_HOST_RUNS_X86_64_V3)
      set(${out_var} "-march=x86-64-v3" PARENT_SCOPE)
    else()
      set(${out_var} "" PARENT_SCOPE)
    endif()
  else()
    set(${out_var} "-march=${ATMO_ARCH}" PARENT_SCOPE)
  endif()
  message(STATUS "atmo: ATMO_ARCH=${ATMO_ARCH}")
endfunction()
