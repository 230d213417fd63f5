# fb_add_shaders(TARGET target SOURCES a.comp b.comp ...)
#
# Compiles each GLSL compute shader to SPIR-V with glslangValidator and embeds it as a C array
# (`--vn NAME_comp`) in a generated header NAME_comp.h under ${CMAKE_BINARY_DIR}/spv. glslang's
# depfile lists every #include, so editing a kernels/ header rebuilds exactly the shaders that use it.
find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)

function(fb_add_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES" ${ARGN})
  set(outdir ${CMAKE_BINARY_DIR}/spv)
  file(MAKE_DIRECTORY ${outdir})
  set(headers)
  foreach(src ${ARG_SOURCES})
    get_filename_component(name ${src} NAME_WE)
    set(var ${name}_comp)
    set(hdr ${outdir}/${var}.h)
    set(dep ${outdir}/${var}.d)
    add_custom_command(
      OUTPUT ${hdr}
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.1 --quiet --vn ${var}
              --depfile ${dep} -o ${hdr} ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPFILE ${dep}
      COMMENT "SPIR-V ${src}"
      VERBATIM)
    list(APPEND headers ${hdr})
  endforeach()
  add_custom_target(${ARG_TARGET} DEPENDS ${headers})
  set(FB_SPV_INCLUDE_DIR ${outdir} PARENT_SCOPE)
endfunction()
