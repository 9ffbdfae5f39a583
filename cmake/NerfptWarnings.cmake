# Warnings as errors on our own code only (third-party headers are included as SYSTEM by their targets).
function(nerfpt_warnings target)
    target_compile_options(${target} PRIVATE
        $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Werror -Wno-missing-field-initializers>)
endfunction()
