/* TEST-ONLY stand-in for Windows' bcryptprimitives.dll, which Wine 8 (Debian 12) does not provide.
 * Rust's standard library (1.78 and later) imports ProcessPrng from it to seed its hash maps; on
 * Windows 10 and later the system DLL is always there, and the FMU ships no shim. This one gives
 * ProcessPrng through RtlGenRandom (advapi32's SystemFunction036), so that the DLL can be loaded
 * under Wine. It is built and placed beside the test driver only. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length); /* RtlGenRandom */

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk)) return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
