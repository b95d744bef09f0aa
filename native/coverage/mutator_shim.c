/* Custom-mutator shim for native-coverage campaigns (`make fuzz-native`).
 *
 * Why: libFuzzer finds the custom mutator and crossover through weak references
 * (LLVMFuzzerCustomMutator, LLVMFuzzerCustomCrossOver). Atheris defines them in
 * atheris/custom_mutator*.so and atheris/custom_crossover*.so, which it imports with
 * RTLD_GLOBAL when atheris.Fuzz() starts, before loading its *built-in* libFuzzer,
 * so the built-in one sees them. A libFuzzer preloaded with LD_PRELOAD (Atheris'
 * asan_with_fuzzer.so, needed to link the clang-instrumented native module) has
 * resolved its weak references at process start, when nothing defined them: they
 * stay NULL and libFuzzer never calls our mutators.
 *
 * This library is preloaded next to asan_with_fuzzer.so, so the weak references
 * resolve here. At call time it forwards to the next definition in the global
 * scope (Atheris' modules, loaded later with RTLD_GLOBAL). When there is none
 * (a campaign run with --mutator=libfuzzer), it falls back to libFuzzer's own
 * mutator (LLVMFuzzerMutate) and produces no crossover. It depends on no Python
 * symbol, so the shells and tools that inherit LD_PRELOAD (-fork, -jobs) load it.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
#include <stdint.h>

typedef size_t (*mutator_fn)(uint8_t *, size_t, size_t, unsigned int);
typedef size_t (*crossover_fn)(const uint8_t *, size_t, const uint8_t *, size_t, uint8_t *,
                               size_t, unsigned int);

size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size);

static mutator_fn next_mutator(void) {
  static mutator_fn cached;
  if (!cached) cached = (mutator_fn)dlsym(RTLD_NEXT, "LLVMFuzzerCustomMutator");
  return cached;
}

static crossover_fn next_crossover(void) {
  static crossover_fn cached;
  if (!cached) cached = (crossover_fn)dlsym(RTLD_NEXT, "LLVMFuzzerCustomCrossOver");
  return cached;
}

size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed) {
  mutator_fn fn = next_mutator();
  if (fn) return fn(data, size, max_size, seed);
  return LLVMFuzzerMutate(data, size, max_size);
}

size_t LLVMFuzzerCustomCrossOver(const uint8_t *data1, size_t size1, const uint8_t *data2,
                                 size_t size2, uint8_t *out, size_t max_out_size,
                                 unsigned int seed) {
  crossover_fn fn = next_crossover();
  if (fn) return fn(data1, size1, data2, size2, out, max_out_size, seed);
  return 0;
}
