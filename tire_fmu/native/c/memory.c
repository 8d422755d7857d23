/* memory.c: every allocation of the tire's C goes through the host's functions (FMI 2.0's
 * calloc-like allocateMemory and freeMemory), or calloc and free for a host without them. */
#include <stdlib.h>

#include "tire.h"

void* mem_alloc(const Memory* mem, size_t count, size_t size)
{
    if (count == 0) count = 1;
    return mem->allocate(count, size);
}

void mem_free(const Memory* mem, void* pointer)
{
    if (pointer != NULL) mem->release(pointer);
}

const Memory* mem_default(void)
{
    static const Memory plain = {calloc, free};
    return &plain;
}
