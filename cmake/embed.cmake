# Writes OUT as a C file defining `const char SYMBOL[]` with the bytes of IN plus a NUL.
file(READ ${IN} content HEX)
string(LENGTH "${content}" n)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${content}")
math(EXPR size "${n} / 2")
file(WRITE ${OUT} "/* Generated from ${IN} by cmake/embed.cmake; do not edit. */\n#include <stddef.h>\nconst char ${SYMBOL}[] = {${bytes}0x00};\nconst size_t ${SYMBOL}_size = ${size};\n")
