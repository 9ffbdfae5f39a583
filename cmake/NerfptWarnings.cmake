# Warnings as errors on our own code only (third-party headers are included as SYSTEM by their targets).
# NERFPT_WERROR=OFF keeps them warnings (a compiler we do not build with every day, e.g. clang for fuzzing).
function(nerfpt_warnings target)
    target_compile_options(${target} PRIVATE
        $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wno-missing-field-initializers>)
    if(NERFPT_WERROR)
        target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-Werror>)
    endif()
endfunction()
