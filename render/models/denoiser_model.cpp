// The denoiser network's ONNX model (denoiser.onnx beside this file, made by tools/denoiser/
// train.py), linked into the library as bytes: the program needs no file at run time. The path
// comes from CMake (CADSYNTH_DENOISER_ONNX); this file is compiled without link-time optimisation,
// which may move top-level assembly away from the symbols it defines.
#ifndef CADSYNTH_DENOISER_ONNX
#error "CADSYNTH_DENOISER_ONNX must name the model file"
#endif

#define CADSYNTH_STRINGIFY2(x) #x
#define CADSYNTH_STRINGIFY(x) CADSYNTH_STRINGIFY2(x)

__asm__(
    ".pushsection .rodata\n"
    ".global cadsynth_denoiser_onnx\n"
    ".global cadsynth_denoiser_onnx_end\n"
    ".balign 16\n"
    "cadsynth_denoiser_onnx:\n"
    ".incbin \"" CADSYNTH_STRINGIFY(CADSYNTH_DENOISER_ONNX) "\"\n"
    "cadsynth_denoiser_onnx_end:\n"
    ".popsection\n");
