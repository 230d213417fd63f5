# fb_add_shaders(TARGET target SOURCES a.comp b.comp ...)
#
# Compiles each GLSL compute shader to SPIR-V with glslangValidator, runs the build's SPIR-V pass
# (cmake/spvexact.c: NoContraction on every float operation, NaN-defined min and max), makes its
# native variant (K_EXACT_NATIVE true, the portable division removed by spirv-opt) and embeds both
# as one C array (`NAME_comp`) in a generated header NAME_comp.h under ${CMAKE_BINARY_DIR}/spv
# (host/io/spvpatch.h picks the variant). The patched module itself is spv/NAME.spv (the SPIR-V
# audit, tests/spirv_audit.py, reads it), the native one spv/native/NAME.spv.
# glslang's depfile lists every #include, so editing a kernels/ header rebuilds exactly the shaders
# that use it.
find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)
find_program(SPIRV_OPT spirv-opt REQUIRED)

add_executable(spvexact ${CMAKE_CURRENT_LIST_DIR}/spvexact.c)

function(fb_add_shaders)
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES" ${ARGN})
  set(outdir ${CMAKE_BINARY_DIR}/spv)
  file(MAKE_DIRECTORY ${outdir}/raw ${outdir}/native)
  set(headers)
  foreach(src ${ARG_SOURCES})
    get_filename_component(name ${src} NAME_WE)
    set(var ${name}_comp)
    set(raw ${outdir}/raw/${name}.spv)
    set(hdr ${outdir}/${var}.h)
    add_custom_command(
      OUTPUT ${raw}
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.1 --quiet --depfile ${raw}.d -o ${raw}
              ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPFILE ${raw}.d
      COMMENT "SPIR-V ${src}"
      VERBATIM)
    set(native ${outdir}/native/${name}.spv)
    add_custom_command(
      OUTPUT ${outdir}/${name}.spv ${native}.pre
      COMMAND spvexact ${raw} ${outdir}/${name}.spv ${native}.pre
      DEPENDS ${raw} spvexact
      COMMENT "SPIR-V ${name}: exact arithmetic pass"
      VERBATIM)
    # The variant for a device whose own division is exact: K_EXACT_NATIVE true, the portable
    # division's code removed (spirv-opt's passes here change no arithmetic).
    add_custom_command(
      OUTPUT ${native}
      COMMAND ${SPIRV_OPT} --eliminate-dead-branches --eliminate-dead-functions --eliminate-dead-code-aggressive
              ${native}.pre -o ${native}
      DEPENDS ${native}.pre
      COMMENT "SPIR-V ${name}: native variant"
      VERBATIM)
    add_custom_command(
      OUTPUT ${hdr}
      COMMAND spvexact --embed ${var} ${outdir}/${name}.spv ${native} ${hdr}
      DEPENDS ${outdir}/${name}.spv ${native} spvexact
      COMMENT "SPIR-V ${name}: embedded"
      VERBATIM)
    list(APPEND headers ${hdr})
  endforeach()
  add_custom_target(${ARG_TARGET} DEPENDS ${headers})
  set(FB_SPV_INCLUDE_DIR ${outdir} PARENT_SCOPE)
endfunction()
