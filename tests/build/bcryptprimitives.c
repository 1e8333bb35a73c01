/* A stand-in for Windows' bcryptprimitives.dll, only for running the Windows CLI under wine 8
 * (tests/build/test_windows_cli.py). Rust's standard library (and getrandom) import ProcessPrng from it; wine 8.0 has
 * no such DLL, so the program cannot start. This one exports ProcessPrng and fills the buffer from
 * RtlGenRandom (advapi32's SystemFunction036), which wine has. Never shipped: Windows has the real DLL.
 *
 *   x86_64-w64-mingw32-gcc -shared -O2 -o bcryptprimitives.dll bcryptprimitives.c -ladvapi32
 */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length)
{
    while (length > 0) {
        ULONG chunk = length > 0x40000000 ? 0x40000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk))
            return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
