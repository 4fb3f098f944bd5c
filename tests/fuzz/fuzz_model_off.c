/* fuzz_model_off.c — libFuzzer target: the OFF model reader on arbitrary
 * bytes (see fuzz_model.h for the property checked). */
#include "fuzz_model.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_model(data, size, PROTO_FMT_OFF);
}
