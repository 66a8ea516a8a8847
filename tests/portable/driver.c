/* A minimal FMI 2.0 co-simulation importer, the same source for Linux (gcc, dlopen) and Windows
 * (mingw-w64, LoadLibrary): loads the FMU's binary, runs an experiment with a step of the input
 * `r`, and prints the chosen outputs every `every` communication steps, one line each:
 *   t <time> r <vr>=<value> ... i <vr>=<value> ...
 * with %.17g, so that two runs can be compared to the last bit. Used by tests/python/test_portable.py
 * to compare the Windows DLL (under Wine) with the Linux library.
 *
 * usage: driver LIBRARY GUID STOP STEP R EVERY REAL_VRS INTEGER_VRS
 *   REAL_VRS, INTEGER_VRS: comma-separated value references. Exit status 0 only if every call
 *   returned fmi2OK. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
typedef HMODULE library_t;
static library_t open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(library_t lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static const char *load_error(void) {
    static char text[64];
    snprintf(text, sizeof text, "LoadLibrary error %lu", (unsigned long)GetLastError());
    return text;
}
#else
#include <dlfcn.h>
typedef void *library_t;
static library_t open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(library_t lib, const char *name) { return dlsym(lib, name); }
static const char *load_error(void) { return dlerror(); }
#endif

/* The FMI 2.0 types this driver uses (fmi2TypesPlatform.h, fmi2FunctionTypes.h). */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef int fmi2Status; /* 0 OK, 1 Warning, 2 Discard, 3 Error, 4 Fatal, 5 Pending */
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, const char *, fmi2Status, const char *,
                                   const char *, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

typedef fmi2Component (*InstantiateFn)(const char *, int, const char *, const char *,
                                     const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
typedef fmi2Status (*SetupExperimentFn)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean,
                                      fmi2Real);
typedef fmi2Status (*SimpleFn)(fmi2Component);
typedef void (*FreeInstanceFn)(fmi2Component);
typedef fmi2Status (*SetRealFn)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2Real *);
typedef fmi2Status (*GetRealFn)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Real *);
typedef fmi2Status (*GetIntegerFn)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Integer *);
typedef fmi2Status (*SetIntegerFn)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2Integer *);
typedef fmi2Status (*DoStepFn)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);

static void logger(fmi2ComponentEnvironment env, const char *instance, fmi2Status status,
                   const char *category, const char *message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] status %d, %s: ", instance, status, category);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

/* Parses "1,2,3" into vrs (at most 64); returns the count. */
static size_t parse_vrs(const char *text, fmi2ValueReference *vrs) {
    size_t n = 0;
    const char *p = text;
    while (*p && n < 64) {
        char *end;
        vrs[n++] = (fmi2ValueReference)strtoul(p, &end, 10);
        p = *end == ',' ? end + 1 : end;
        if (end == p && *end != ',') break;
    }
    return n;
}

#define LOAD(type, name)                                                                           \
    type name = (type)symbol(lib, "fmi2" #name);                                                   \
    if (!name) {                                                                                   \
        fprintf(stderr, "missing fmi2" #name "\n");                                                \
        return 2;                                                                                  \
    }
#define CHECK(call)                                                                                \
    if ((call) != 0) {                                                                             \
        fprintf(stderr, "%s did not return fmi2OK\n", #call);                                      \
        return 3;                                                                                  \
    }

int main(int argc, char **argv) {
    if (argc != 9 && argc != 10) {
        fprintf(stderr, "usage: %s LIBRARY GUID STOP STEP R EVERY REAL_VRS INTEGER_VRS [SETTINGS]\n"
                        "  SETTINGS: VR:TYPE:VALUE,... set before initialisation; TYPE r (Real),\n"
                        "  i (Integer) or b (Boolean, 0 or 1)\n", argv[0]);
        return 1;
    }
    double stop = atof(argv[3]), step = atof(argv[4]), r = atof(argv[5]);
    long every = atol(argv[6]);
    fmi2ValueReference rvrs[64], ivrs[64], r_vr = 1;
    size_t nr = parse_vrs(argv[7], rvrs), ni = parse_vrs(argv[8], ivrs);
    fmi2Real reals[64];
    fmi2Integer ints[64];

    library_t lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], load_error());
        return 2;
    }
    LOAD(InstantiateFn, Instantiate)
    LOAD(SetupExperimentFn, SetupExperiment)
    LOAD(SimpleFn, EnterInitializationMode)
    LOAD(SimpleFn, ExitInitializationMode)
    LOAD(SimpleFn, Terminate)
    LOAD(FreeInstanceFn, FreeInstance)
    LOAD(SetRealFn, SetReal)
    LOAD(GetRealFn, GetReal)
    LOAD(GetIntegerFn, GetInteger)
    LOAD(SetIntegerFn, SetInteger)
    LOAD(SetIntegerFn, SetBoolean)
    LOAD(DoStepFn, DoStep)

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = Instantiate("driver", 1 /* fmi2CoSimulation */, argv[2], "", &callbacks, 0, 0);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate failed\n");
        return 3;
    }
    CHECK(SetupExperiment(c, 0, 0.0, 0.0, 1, stop))
    CHECK(EnterInitializationMode(c))
    CHECK(SetReal(c, &r_vr, 1, &r))
    for (const char *p = argc == 10 ? argv[9] : ""; *p;) {
        char *end, type;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(p, &end, 10);
        if (*end != ':' || !end[1] || end[2] != ':') {
            fprintf(stderr, "bad setting at '%s'\n", p);
            return 1;
        }
        type = end[1];
        p = end + 3;
        if (type == 'r') {
            fmi2Real v = strtod(p, &end);
            CHECK(SetReal(c, &vr, 1, &v))
        } else {
            fmi2Integer v = (fmi2Integer)strtol(p, &end, 10);
            if (type == 'i') {
                CHECK(SetInteger(c, &vr, 1, &v))
            } else {
                CHECK(SetBoolean(c, &vr, 1, &v))
            }
        }
        p = *end == ',' ? end + 1 : end;
    }
    CHECK(ExitInitializationMode(c))
    long n = (long)(stop / step + 0.5);
    for (long k = 0; k <= n; k++) {
        double t = k * step;
        if (k % every == 0 || k == n) {
            CHECK(GetReal(c, rvrs, nr, reals))
            CHECK(GetInteger(c, ivrs, ni, ints))
            printf("t %.17g r", t);
            for (size_t j = 0; j < nr; j++) printf(" %u=%.17g", rvrs[j], reals[j]);
            printf(" i");
            for (size_t j = 0; j < ni; j++) printf(" %u=%d", ivrs[j], ints[j]);
            printf("\n");
        }
        if (k < n) CHECK(DoStep(c, t, step, 1))
    }
    CHECK(Terminate(c))
    FreeInstance(c);
    return 0;
}
