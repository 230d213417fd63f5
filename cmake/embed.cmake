# cmake -DIN=FILE -DOUT=HEADER -DNAME=VAR -P embed.cmake
#
# Embeds a text file as a NUL-terminated C array `static const char VAR[]` in HEADER (the default
# scene, docs/examples/gallery-night.json, the way shaders are embedded as SPIR-V).
file(READ ${IN} hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "(0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,)" "\\1\n    "
       bytes "${bytes}")
file(WRITE ${OUT}.tmp "/* Generated from ${IN} by cmake/embed.cmake: do not edit. */\nstatic const char ${NAME}[] = {\n    ${bytes}0x00};\n")
file(RENAME ${OUT}.tmp ${OUT})
