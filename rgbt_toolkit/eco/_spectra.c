/* Compiled loops of ECO's filter arithmetic on complex64 spectra: the two channel/sample contractions that every
 * detection score and every CG iteration of the filter update evaluates, and the spatial regularisation W^H W f that
 * every CG iteration applies to every block.
 *
 * Why C: in numpy each contraction is a product into an (n, C, Ny, Nxh) temporary followed by a reduction, about
 * six passes over the 10 MB sample store at 50 samples; the filter update spent 7 ms per CG iteration there. Here
 * each is one pass with no temporary, and the GIL is released so the RGB and thermal trackers use both cores.
 *
 * The arithmetic follows numpy's operation by operation in float32 (the complex product with or without fused
 * multiply-add as numpy's SIMD loops form it on the same CPU, see PRODUCT; no other contraction: compiled with
 * -ffp-contract=off; sums in numpy's order along an outer axis), so the results are bit-identical to the numpy
 * expressions in rgbt_toolkit/eco/optimize.py on the contiguous spectra ECO passes, which the tests compare against
 * (numpy's own strided and broadcast paths of tiny arrays skip the fused product, and so may differ by an ulp).
 *
 * Arrays arrive through the buffer protocol, C-contiguous complex64 (interleaved float32 pairs), with their shapes as
 * separate arguments; each function checks every buffer's byte length against those shapes before touching memory.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

/* The FMA variants exist only where numpy picks them at run time the same way: x86 with GCC or Clang. Elsewhere
 * (ARM, other compilers) the plain products are used, and the results agree with numpy to float32 rounding. */
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define FMA_VARIANT 1
#define ALWAYS_INLINE __attribute__((always_inline))
#define FMA_TARGET __attribute__((target("fma")))
#else
#define FMA_VARIANT 0
#define ALWAYS_INLINE
#define FMA_TARGET
#endif

static int check_len(Py_buffer *b, Py_ssize_t count, const char *name) {
    if (count < 0 || b->len != count * 8) {
        PyErr_Format(PyExc_ValueError, "%s: buffer has %zd bytes, shape needs %zd complex64 values", name, b->len,
                     count);
        return 0;
    }
    return 1;
}

/* The complex product as numpy computes it: where the CPU has FMA, numpy's SIMD loops form the real part as
 * fma(ar, br, -(ai bi)) and the imaginary part as fma(ar, bi, ai br); without FMA, plainly. The loops below are
 * compiled twice (fused = 1 in a function built for FMA, 0 in a plain one) and picked at run time the same way. */
#define PRODUCT(ar, ai, br, bi, re, im)                                                                          \
    do {                                                                                                         \
        if (fused) {                                                                                             \
            re = fmaf(ar, br, -((ai) * (bi)));                                                                   \
            im = fmaf(ar, bi, (ai) * (br));                                                                      \
        } else {                                                                                                 \
            re = (ar) * (br) - (ai) * (bi);                                                                      \
            im = (ar) * (bi) + (ai) * (br);                                                                      \
        }                                                                                                        \
    } while (0)

/* out[j, q] = sum_ch z[j, ch, q] f[ch, q]; the first channel's product starts the sum, as numpy's reduction */
static inline ALWAYS_INLINE void products_loop(const float *z, const float *f, Py_ssize_t lead, Py_ssize_t c,
                                               Py_ssize_t k, float *out, const int fused) {
    for (Py_ssize_t j = 0; j < lead; j++) {
        float *o = out + 2 * j * k;
        const float *zj = z + 2 * j * c * k;
        for (Py_ssize_t q = 0; q < k; q++)
            PRODUCT(zj[2 * q], zj[2 * q + 1], f[2 * q], f[2 * q + 1], o[2 * q], o[2 * q + 1]);
        for (Py_ssize_t ch = 1; ch < c; ch++) {
            const float *zc = zj + 2 * ch * k, *fc = f + 2 * ch * k;
            for (Py_ssize_t q = 0; q < k; q++) {
                float re, im;
                PRODUCT(zc[2 * q], zc[2 * q + 1], fc[2 * q], fc[2 * q + 1], re, im);
                o[2 * q] += re;
                o[2 * q + 1] += im;
            }
        }
    }
}

/* out[ch, q] = sum_j conj(z[j, ch, q]) p[j, q]: numpy conjugates first (ai = -zi), then multiplies */
static inline ALWAYS_INLINE void backprojection_loop(const float *z, const float *p, Py_ssize_t n, Py_ssize_t c,
                                                     Py_ssize_t k, float *out, const int fused) {
    for (Py_ssize_t j = 0; j < n; j++) {
        const float *pj = p + 2 * j * k;
        for (Py_ssize_t ch = 0; ch < c; ch++) {
            const float *zc = z + 2 * (j * c + ch) * k;
            float *o = out + 2 * ch * k;
            if (j == 0)
                for (Py_ssize_t q = 0; q < k; q++)
                    PRODUCT(zc[2 * q], -zc[2 * q + 1], pj[2 * q], pj[2 * q + 1], o[2 * q], o[2 * q + 1]);
            else
                for (Py_ssize_t q = 0; q < k; q++) {
                    float re, im;
                    PRODUCT(zc[2 * q], -zc[2 * q + 1], pj[2 * q], pj[2 * q + 1], re, im);
                    o[2 * q] += re;
                    o[2 * q + 1] += im;
                }
        }
    }
}

FMA_TARGET static void products_fused(const float *z, const float *f, Py_ssize_t lead, Py_ssize_t c, Py_ssize_t k,
                                      float *out) {
    products_loop(z, f, lead, c, k, out, 1);
}
static void products_plain(const float *z, const float *f, Py_ssize_t lead, Py_ssize_t c, Py_ssize_t k, float *out) {
    products_loop(z, f, lead, c, k, out, 0);
}
FMA_TARGET static void backprojection_fused(const float *z, const float *p, Py_ssize_t n, Py_ssize_t c, Py_ssize_t k,
                                            float *out) {
    backprojection_loop(z, p, n, c, k, out, 1);
}
static void backprojection_plain(const float *z, const float *p, Py_ssize_t n, Py_ssize_t c, Py_ssize_t k,
                                 float *out) {
    backprojection_loop(z, p, n, c, k, out, 0);
}

static int cpu_has_fma = 0; /* the CPU has FMA (and this build has the FMA variants): set once when the module loads */

static int has_fma(void) {
#if FMA_VARIANT
    __builtin_cpu_init();
    return __builtin_cpu_supports("fma");
#else
    return 0;
#endif
}

/* channel_products(z, f, lead, c, k, out): out[j, q] = sum_ch z[j, ch, q] f[ch, q] for z (lead, c, k), f (c, k),
 * out (lead, k); numpy: (z * f).sum(axis=-3). */
static PyObject *channel_products(PyObject *self, PyObject *args) {
    Py_buffer zb, fb, ob;
    Py_ssize_t lead, c, k;
    if (!PyArg_ParseTuple(args, "y*y*nnnw*", &zb, &fb, &lead, &c, &k, &ob)) return NULL;
    PyObject *result = NULL;
    if (!check_len(&zb, lead * c * k, "z") || !check_len(&fb, c * k, "f") || !check_len(&ob, lead * k, "out")) goto done;
    if (c < 1) {
        PyErr_SetString(PyExc_ValueError, "channel_products: no channels to sum");
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    (cpu_has_fma ? products_fused : products_plain)(zb.buf, fb.buf, lead, c, k, ob.buf);
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&zb); PyBuffer_Release(&fb); PyBuffer_Release(&ob);
    return result;
}

/* sample_backprojection(z, p, n, c, k, out): out[ch, q] = sum_j conj(z[j, ch, q]) p[j, q] for z (n, c, k), p (n, k),
 * out (c, k); numpy: (np.conj(z) * p[:, None]).sum(axis=0). */
static PyObject *sample_backprojection(PyObject *self, PyObject *args) {
    Py_buffer zb, pb, ob;
    Py_ssize_t n, c, k;
    if (!PyArg_ParseTuple(args, "y*y*nnnw*", &zb, &pb, &n, &c, &k, &ob)) return NULL;
    PyObject *result = NULL;
    if (!check_len(&zb, n * c * k, "z") || !check_len(&pb, n * k, "p") || !check_len(&ob, c * k, "out")) goto done;
    if (n < 1) {
        PyErr_SetString(PyExc_ValueError, "sample_backprojection: no samples to sum");
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    (cpu_has_fma ? backprojection_fused : backprojection_plain)(zb.buf, pb.buf, n, c, k, ob.buf);
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&zb); PyBuffer_Release(&pb); PyBuffer_Release(&ob);
    return result;
}

/* W^H W f of ECO's spatial regularisation for one channel after another, as the numpy code in
 * rgbt_toolkit/eco/regularization.py computes it: the half-layout spectrum x (ny, nxh) extended by Hermitian symmetry
 * to the cols = min(kw - 1, nxh - 1) columns left of kx = 0, convolved in full with the window's coefficients k
 * (kh, kw), then in the valid part with k flipped, and the kx >= 0 half kept. Every sum starts at zero and adds its
 * terms in numpy's order (the kernel's non-zero entries row by row), each term k x formed exactly (numpy's complex
 * product with a real factor rounds the same), so the result is the numpy code's bit for bit. The two work planes
 * are the caller's. */
static void regularisation_loop(const float *x_all, const float *k, Py_ssize_t lead, Py_ssize_t ny, Py_ssize_t nxh,
                                Py_ssize_t kh, Py_ssize_t kw, float *out_all, float *full, float *mid) {
    const Py_ssize_t cols = kw - 1 < nxh - 1 ? kw - 1 : nxh - 1;
    const Py_ssize_t w = nxh + cols, h2 = ny + kh - 1, w2 = w + kw - 1;
    for (Py_ssize_t c = 0; c < lead; c++) {
        const float *x = x_all + 2 * c * ny * nxh;
        float *out = out_all + 2 * c * ny * nxh;
        for (Py_ssize_t y = 0; y < ny; y++) {
            float *row = full + 2 * y * w;
            const float *mirror = x + 2 * (ny - 1 - y) * nxh; /* X[-ky, -kx] = conj(X[ky, kx]) */
            for (Py_ssize_t u = 0; u < cols; u++) {
                row[2 * u] = mirror[2 * (cols - u)];
                row[2 * u + 1] = -mirror[2 * (cols - u) + 1];
            }
            memcpy(row + 2 * cols, x + 2 * y * nxh, sizeof(float) * 2 * nxh);
        }
        /* full convolution: tap by tap, each adding k x to the plane shifted by it, as numpy's loop does */
        memset(mid, 0, sizeof(float) * 2 * h2 * w2);
        for (Py_ssize_t i = 0; i < kh; i++)
            for (Py_ssize_t j = 0; j < kw; j++) {
                const float kij = k[i * kw + j];
                if (kij == 0.0f) continue;
                for (Py_ssize_t y = 0; y < ny; y++) {
                    float *m = mid + 2 * ((y + i) * w2 + j);
                    const float *v = full + 2 * y * w;
                    for (Py_ssize_t t = 0; t < 2 * w; t++) m[t] += kij * v[t];
                }
            }
        /* valid convolution with k flipped, only at the kx >= 0 columns that are returned */
        memset(out, 0, sizeof(float) * 2 * ny * nxh);
        for (Py_ssize_t i = 0; i < kh; i++)
            for (Py_ssize_t j = 0; j < kw; j++) {
                if (k[i * kw + j] == 0.0f) continue;
                const float kflip = k[(kh - 1 - i) * kw + (kw - 1 - j)];
                for (Py_ssize_t y = 0; y < ny; y++) {
                    float *o = out + 2 * y * nxh;
                    const float *v = mid + 2 * ((y + i) * w2 + cols + j);
                    for (Py_ssize_t t = 0; t < 2 * nxh; t++) o[t] += kflip * v[t];
                }
            }
    }
}

/* regularisation(x, k, lead, ny, nxh, kh, kw, out): W^H W f for lead half-layout complex64 spectra x (lead, ny, nxh)
 * and the float32 window coefficients k (kh, kw); numpy: rgbt_toolkit.eco.regularization.apply_reg. */
static PyObject *regularisation(PyObject *self, PyObject *args) {
    Py_buffer xb, kb, ob;
    Py_ssize_t lead, ny, nxh, kh, kw;
    if (!PyArg_ParseTuple(args, "y*y*nnnnnw*", &xb, &kb, &lead, &ny, &nxh, &kh, &kw, &ob)) return NULL;
    PyObject *result = NULL;
    float *work = NULL;
    if (!check_len(&xb, lead * ny * nxh, "x") || !check_len(&ob, lead * ny * nxh, "out")) goto done;
    if (ny < 1 || nxh < 1 || kh < 1 || kw < 1 || kb.len != kh * kw * 4) {
        PyErr_Format(PyExc_ValueError, "regularisation: k has %zd bytes for a %zd x %zd float32 kernel, spectra "
                     "%zd x %zd", kb.len, kh, kw, ny, nxh);
        goto done;
    }
    const Py_ssize_t cols = kw - 1 < nxh - 1 ? kw - 1 : nxh - 1, w = nxh + cols;
    work = PyMem_RawMalloc(sizeof(float) * 2 * (ny * w + (ny + kh - 1) * (w + kw - 1)));
    if (work == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    regularisation_loop(xb.buf, kb.buf, lead, ny, nxh, kh, kw, ob.buf, work, work + 2 * ny * w);
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyMem_RawFree(work);
    PyBuffer_Release(&xb); PyBuffer_Release(&kb); PyBuffer_Release(&ob);
    return result;
}

static PyMethodDef methods[] = {
    {"channel_products", channel_products, METH_VARARGS, "sum over channels of z * f for complex64 spectra."},
    {"sample_backprojection", sample_backprojection, METH_VARARGS, "sum over samples of conj(z) * p, complex64."},
    {"regularisation", regularisation, METH_VARARGS, "W^H W f of ECO's spatial regularisation, complex64."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_spectra", "Compiled loops of ECO's filter arithmetic.",
                                    -1, methods};

PyMODINIT_FUNC PyInit__spectra(void) {
    cpu_has_fma = has_fma();
    return PyModule_Create(&module);
}
