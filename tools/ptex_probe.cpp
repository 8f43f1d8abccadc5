// Prints the Ptex library's values at pseudo-random lookups of a Ptex file, through the
// filter pbrt asks for (f_bspline; on triangle meshes the library's triangle filter),
// with pbrt's cache settings (premultiplied alpha). One line per lookup:
//   face u v dudx dvdx dudy dvdy value...
// Half the lookups have no footprint, half a small or a large one; some sit on face
// edges. tests/data/ptex/probes-NAME.txt are its output for the files of
// tools/make_ptex.py (N = 600, SEED = 7); the unit tests of src/textures/ptex/filter.rs
// hold our filter to them.
//
// Build against the Ptex library (wdas/ptex; pbrt-v4's build, tools/build-pbrt-v4.sh,
// makes libPtex.a):
//   g++ -O2 -o ptex_probe tools/ptex_probe.cpp -I PTEX/src/ptex -I BUILD/src/ext/ptex/src/ptex \
//       BUILD/src/ext/ptex/src/ptex/libPtex.a -lz -lpthread
//   ./ptex_probe FILE N SEED
#include <Ptexture.h>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
static uint64_t s;
static float rnd() { s = s * 6364136223846793005ULL + 1442695040888963407ULL; return (s >> 40) / float(1 << 24); }
int main(int argc, char **argv) {
    Ptex::String err;
    Ptex::PtexCache *cache = Ptex::PtexCache::create(100, 1ull << 32, true, nullptr, nullptr);
    Ptex::PtexTexture *t = cache->get(argv[1], err);
    if (!t) { fprintf(stderr, "%s\n", err.c_str()); return 1; }
    int n = atoi(argv[2]); s = atoi(argv[3]);
    Ptex::PtexFilter::Options opts(Ptex::PtexFilter::f_bspline);
    Ptex::PtexFilter *f = Ptex::PtexFilter::getFilter(t, opts);
    int nc = t->numChannels();
    for (int i = 0; i < n; i++) {
        int face = int(rnd() * t->numFaces());
        float u = rnd(), v = rnd();
        if (i % 7 == 0) u = (i % 2) ? 0.f : 1.f;
        if (i % 11 == 0) v = (i % 3) ? 0.f : 1.f;
        float w[4] = {0, 0, 0, 0};
        if (i % 2) { float m = rnd() < 0.5 ? 0.02f : 0.4f; for (int k = 0; k < 4; k++) w[k] = (rnd() - 0.5f) * m; }
        float r[4] = {0, 0, 0, 0};
        f->eval(r, 0, nc, face, u, v, w[0], w[1], w[2], w[3]);
        printf("%d %.9g %.9g %.9g %.9g %.9g %.9g", face, u, v, w[0], w[1], w[2], w[3]);
        for (int c = 0; c < nc; c++) printf(" %.9g", r[c]);
        printf("\n");
    }
    f->release(); t->release(); cache->release();
}
