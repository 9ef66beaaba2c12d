/* version.c: the library's version at run time, to compare with the cbvh.h a program was built against. */
#include "cbvh.h"

uint32_t cbvh_version(void)
{
    return CBVH_VERSION_NUMBER;
}

const char *cbvh_version_string(void)
{
    return CBVH_VERSION_STRING;
}
