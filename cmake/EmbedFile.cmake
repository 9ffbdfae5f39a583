# cmake -DINPUT=file -DOUTPUT=file.cpp -DNAME=symbol -P EmbedFile.cmake: writes a C++ source that defines
# `const unsigned char NAME[]` with the bytes of INPUT and `const size_t NAME_size`.
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" digits)
math(EXPR bytes "${digits} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," array "${hex}")
file(WRITE "${OUTPUT}" "// Generated from ${INPUT} by cmake/EmbedFile.cmake; do not edit.\n#include <cstddef>\n"
     "extern const unsigned char ${NAME}[] = {${array}};\nextern const size_t ${NAME}_size = ${bytes};\n")
