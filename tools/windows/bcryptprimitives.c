/* A stand-in for bcryptprimitives.dll, for running indra.exe under Wine 8 only: Rust's standard
 * library (1.78 and later) takes its random numbers from ProcessPrng in that DLL, which Windows
 * 10 and 11 ship and Wine 8 lacks. It answers from advapi32's RtlGenRandom (SystemFunction036),
 * which Wine has. Never packaged: real Windows brings its own. */
#include <windows.h>

__declspec(dllimport) BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x7fffffff ? 0x7fffffff : (ULONG)length;
        if (!SystemFunction036(data, chunk)) {
            return FALSE;
        }
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
