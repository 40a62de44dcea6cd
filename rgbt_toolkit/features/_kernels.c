/* Compiled inner loops of the ECO feature path (fHOG votes, cell reads at several scales, the tent blur evaluated
 * only at the reads of one scale, fHOG normalisation).
 *
 * Why C: the numpy versions of these loops cost about 20 ms of the 30-40 ms an ECO-hc search takes on the 2-core
 * target machine, mostly in temporaries (fancy-index gathers, 4 block-corner passes over 7 x 63 x 63 x 18 arrays).
 * Each function here makes one pass, and releases the GIL so the RGB and thermal trackers run on both cores.
 *
 * The arithmetic follows the numpy definitions operation by operation in float32 (no fused multiply-add: the module
 * is compiled with -ffp-contract=off), so the cell reads and the votes are bit-identical to them; the fHOG texture
 * channels sum in a fixed order where numpy used BLAS (differences of one float32 ulp). The numpy definitions live
 * in tests/features/numpy_reference.py and the tests compare against them. tent_cells replaces OpenCV's whole-map
 * blur followed by bilinear_cells; it sums the same terms in another order (2e-6 relative, tested).
 *
 * Arrays arrive through the buffer protocol, C-contiguous, with their shapes as separate arguments; the Python
 * wrappers (rgbt_toolkit/features/kernels.py) check dtypes and shapes, and each function here checks every buffer's
 * byte length against those shapes before touching memory.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

#define N_ORIENT 18

static int check_len(Py_buffer *b, Py_ssize_t count, Py_ssize_t item, const char *name) {
    if (b->len != count * item) {
        PyErr_Format(PyExc_ValueError, "%s: buffer has %zd bytes, shape needs %zd", name, b->len, count * item);
        return 0;
    }
    return 1;
}

/* Bilinear read positions along one axis, as pooling._bilinear_rows: clamp to [0, size-1], lower and upper index,
 * upper weight rounded to float32. */
static void axis_stencil(const double *pos, Py_ssize_t n, Py_ssize_t size, Py_ssize_t *i0, Py_ssize_t *i1, float *w) {
    for (Py_ssize_t k = 0; k < n; k++) {
        double p = pos[k];
        if (p < 0.0) p = 0.0;
        if (p > (double)(size - 1)) p = (double)(size - 1);
        double f = floor(p);
        i0[k] = (Py_ssize_t)f;
        i1[k] = i0[k] + 1 < size - 1 ? i0[k] + 1 : size - 1;
        w[k] = (float)(p - f);
    }
}

/* bilinear_cells(fmap, h, w, d, rows, cols, s, ny, nx, out): out[k, i, j, :] = fmap read bilinearly at
 * (rows[k, i], cols[k, j]) in map pixels. */
static PyObject *bilinear_cells(PyObject *self, PyObject *args) {
    Py_buffer fb, rb, cb, ob;
    Py_ssize_t h, w, d, s, ny, nx;
    if (!PyArg_ParseTuple(args, "y*nnny*y*nnnw*", &fb, &h, &w, &d, &rb, &cb, &s, &ny, &nx, &ob)) return NULL;
    PyObject *result = NULL;
    Py_ssize_t *iy0 = NULL, *iy1 = NULL, *ix0 = NULL, *ix1 = NULL;
    float *wy = NULL, *wx = NULL;
    if (!check_len(&fb, h * w * d, 4, "fmap") || !check_len(&rb, s * ny, 8, "rows") || !check_len(&cb, s * nx, 8, "cols")
        || !check_len(&ob, s * ny * nx * d, 4, "out"))
        goto done;
    if (h < 1 || w < 1) {
        PyErr_SetString(PyExc_ValueError, "fmap: empty map");
        goto done;
    }
    iy0 = PyMem_Malloc(sizeof(Py_ssize_t) * (ny + 1));
    iy1 = PyMem_Malloc(sizeof(Py_ssize_t) * (ny + 1));
    ix0 = PyMem_Malloc(sizeof(Py_ssize_t) * (nx + 1));
    ix1 = PyMem_Malloc(sizeof(Py_ssize_t) * (nx + 1));
    wy = PyMem_Malloc(sizeof(float) * (ny + 1));
    wx = PyMem_Malloc(sizeof(float) * (nx + 1));
    if (!iy0 || !iy1 || !ix0 || !ix1 || !wy || !wx) {
        PyErr_NoMemory();
        goto done;
    }
    const float *fmap = fb.buf;
    const double *rows = rb.buf, *cols = cb.buf;
    float *out = ob.buf;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < s; k++) {
        axis_stencil(rows + k * ny, ny, h, iy0, iy1, wy);
        axis_stencil(cols + k * nx, nx, w, ix0, ix1, wx);
        for (Py_ssize_t i = 0; i < ny; i++) {
            const float by = wy[i], ay = 1.0f - by;
            const float *top = fmap + iy0[i] * w * d, *bot = fmap + iy1[i] * w * d;
            float *o = out + ((k * ny + i) * nx) * d;
            for (Py_ssize_t j = 0; j < nx; j++) {
                const float bx = wx[j], ax = 1.0f - bx;
                const float *t0 = top + ix0[j] * d, *t1 = top + ix1[j] * d;
                const float *b0 = bot + ix0[j] * d, *b1 = bot + ix1[j] * d;
                for (Py_ssize_t c = 0; c < d; c++) {
                    float t = t0[c] * ax + t1[c] * bx;
                    float b = b0[c] * ax + b1[c] * bx;
                    o[j * d + c] = t * ay + b * by;
                }
            }
        }
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyMem_Free(iy0); PyMem_Free(iy1); PyMem_Free(ix0); PyMem_Free(ix1); PyMem_Free(wy); PyMem_Free(wx);
    PyBuffer_Release(&fb); PyBuffer_Release(&rb); PyBuffer_Release(&cb); PyBuffer_Release(&ob);
    return result;
}

/* Tent-then-bilinear read positions along one axis: the 7-tap tent [1 2 3 4 3 2 1] / 16 (replicated borders)
 * followed by the bilinear read at pos, as one 8-tap stencil per position: idx (n, 8) clamped pixel indices, wt
 * (n, 8) their weights. */
static void tent_stencil(const double *pos, Py_ssize_t n, Py_ssize_t size, Py_ssize_t *idx, float *wt) {
    static const float tent[7] = {1.0f / 16, 2.0f / 16, 3.0f / 16, 4.0f / 16, 3.0f / 16, 2.0f / 16, 1.0f / 16};
    for (Py_ssize_t k = 0; k < n; k++) {
        double p = pos[k];
        if (p < 0.0) p = 0.0;
        if (p > (double)(size - 1)) p = (double)(size - 1);
        double f = floor(p);
        const Py_ssize_t i0 = (Py_ssize_t)f;
        const float b = (float)(p - f), a = 1.0f - b;
        for (int m = 0; m < 8; m++) {
            Py_ssize_t i = i0 - 3 + m;
            idx[k * 8 + m] = i < 0 ? 0 : (i > size - 1 ? size - 1 : i);
            wt[k * 8 + m] = (m < 7 ? a * tent[m] : 0.0f) + (m > 0 ? b * tent[m - 1] : 0.0f);
        }
    }
}

/* tent_cells(fmap, h, w, d, rows, cols, s, ny, nx, out): as bilinear_cells, but of the map blurred by the tent
 * (replicated borders), the blur evaluated only where the reads need it: per scale, one pass down the columns at the
 * ny read rows (whole rows, contiguous), then one along each of those rows at the nx read columns. For one scale of
 * stride-4 cells that is about a third of the work of blurring the whole map first; for several scales it is more,
 * so callers use it for one. */
static PyObject *tent_cells(PyObject *self, PyObject *args) {
    Py_buffer fb, rb, cb, ob;
    Py_ssize_t h, w, d, s, ny, nx;
    if (!PyArg_ParseTuple(args, "y*nnny*y*nnnw*", &fb, &h, &w, &d, &rb, &cb, &s, &ny, &nx, &ob)) return NULL;
    PyObject *result = NULL;
    Py_ssize_t *iy = NULL, *ix = NULL;
    float *wy = NULL, *wx = NULL, *down = NULL;
    if (!check_len(&fb, h * w * d, 4, "fmap") || !check_len(&rb, s * ny, 8, "rows") || !check_len(&cb, s * nx, 8, "cols")
        || !check_len(&ob, s * ny * nx * d, 4, "out"))
        goto done;
    if (h < 1 || w < 1 || d < 1) {
        PyErr_SetString(PyExc_ValueError, "fmap: empty map");
        goto done;
    }
    iy = PyMem_Malloc(sizeof(Py_ssize_t) * 8 * (ny + 1));
    ix = PyMem_Malloc(sizeof(Py_ssize_t) * 8 * (nx + 1));
    wy = PyMem_Malloc(sizeof(float) * 8 * (ny + 1));
    wx = PyMem_Malloc(sizeof(float) * 8 * (nx + 1));
    down = PyMem_Malloc(sizeof(float) * w * d);
    if (!iy || !ix || !wy || !wx || !down) {
        PyErr_NoMemory();
        goto done;
    }
    const float *fmap = fb.buf;
    const double *rows = rb.buf, *cols = cb.buf;
    float *out = ob.buf;
    const Py_ssize_t row_len = w * d;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < s; k++) {
        tent_stencil(rows + k * ny, ny, h, iy, wy);
        tent_stencil(cols + k * nx, nx, w, ix, wx);
        for (Py_ssize_t i = 0; i < ny; i++) {
            /* down the columns: the blurred-and-read row i, whole width */
            const float *src0 = fmap + iy[i * 8] * row_len;
            const float w0 = wy[i * 8];
            for (Py_ssize_t q = 0; q < row_len; q++) down[q] = w0 * src0[q];
            for (int m = 1; m < 8; m++) {
                const float *src = fmap + iy[i * 8 + m] * row_len;
                const float wm = wy[i * 8 + m];
                for (Py_ssize_t q = 0; q < row_len; q++) down[q] += wm * src[q];
            }
            /* along that row, at the column reads */
            float *o = out + ((k * ny + i) * nx) * d;
            for (Py_ssize_t j = 0; j < nx; j++) {
                const Py_ssize_t *col = ix + j * 8;
                const float *wt = wx + j * 8;
                float *oj = o + j * d;
                const float *a0 = down + col[0] * d;
                for (Py_ssize_t c = 0; c < d; c++) oj[c] = wt[0] * a0[c];
                for (int m = 1; m < 8; m++) {
                    const float *src = down + col[m] * d;
                    const float wm = wt[m];
                    for (Py_ssize_t c = 0; c < d; c++) oj[c] += wm * src[c];
                }
            }
        }
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyMem_Free(iy); PyMem_Free(ix); PyMem_Free(wy); PyMem_Free(wx); PyMem_Free(down);
    PyBuffer_Release(&fb); PyBuffer_Release(&rb); PyBuffer_Release(&cb); PyBuffer_Release(&ob);
    return result;
}

/* strongest_gradient(gx, gy, n, out_gx, out_gy): per pixel, the colour channel (of 3) with the largest squared
 * magnitude; ties go to the earlier channel between 0 and 1, to channel 2 only when strictly larger. */
static PyObject *strongest_gradient(PyObject *self, PyObject *args) {
    Py_buffer xb, yb, oxb, oyb;
    Py_ssize_t n;
    if (!PyArg_ParseTuple(args, "y*y*nw*w*", &xb, &yb, &n, &oxb, &oyb)) return NULL;
    PyObject *result = NULL;
    if (!check_len(&xb, n * 3, 4, "gx") || !check_len(&yb, n * 3, 4, "gy") || !check_len(&oxb, n, 4, "out_gx")
        || !check_len(&oyb, n, 4, "out_gy"))
        goto done;
    const float *gx = xb.buf, *gy = yb.buf;
    float *ox = oxb.buf, *oy = oyb.buf;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t p = 0; p < n; p++) {
        const float *x = gx + 3 * p, *y = gy + 3 * p;
        float m0 = x[0] * x[0] + y[0] * y[0], m1 = x[1] * x[1] + y[1] * y[1], m2 = x[2] * x[2] + y[2] * y[2];
        int c = m0 >= m1 ? 0 : 1;
        float m01 = c == 0 ? m0 : m1;
        if (m2 > m01) c = 2;
        ox[p] = x[c];
        oy[p] = y[c];
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&xb); PyBuffer_Release(&yb); PyBuffer_Release(&oxb); PyBuffer_Release(&oyb);
    return result;
}

/* orientation_votes(mag, theta, n, out): out (n, 18) zeroed, then each pixel's magnitude split linearly between the
 * two nearest of 18 orientation bins over [0, 2pi). */
static PyObject *orientation_votes(PyObject *self, PyObject *args) {
    Py_buffer mb, tb, ob;
    Py_ssize_t n;
    if (!PyArg_ParseTuple(args, "y*y*nw*", &mb, &tb, &n, &ob)) return NULL;
    PyObject *result = NULL;
    if (!check_len(&mb, n, 4, "mag") || !check_len(&tb, n, 4, "theta") || !check_len(&ob, n * N_ORIENT, 4, "out"))
        goto done;
    const float *mag = mb.buf, *theta = tb.buf;
    float *out = ob.buf;
    const float bins_per_radian = (float)(N_ORIENT / (2.0 * 3.14159265358979323846));
    Py_BEGIN_ALLOW_THREADS
    memset(out, 0, sizeof(float) * n * N_ORIENT);
    for (Py_ssize_t p = 0; p < n; p++) {
        float b = theta[p] * bins_per_radian;
        if (!(b >= 0.0f && b <= (float)N_ORIENT)) b = 0.0f; /* never out of the row, even for NaN or a bad angle */
        float b0f = floorf(b);
        float fo = b - b0f;
        long b0 = (long)b0f;
        if (b0 >= N_ORIENT) b0 -= N_ORIENT;
        long b1 = b0 + 1 == N_ORIENT ? 0 : b0 + 1;
        float m = mag[p];
        float *o = out + p * N_ORIENT;
        o[b0] = m * (1.0f - fo);
        o[b1] += m * fo;
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyBuffer_Release(&mb); PyBuffer_Release(&tb); PyBuffer_Release(&ob);
    return result;
}

/* fhog_normalise(hist, s, ny, nx, out): 18-bin cell histograms (s, ny, nx, 18) -> the 31 fHOG channels; see
 * fhog.fhog_from_histograms for the definition. */
static PyObject *fhog_normalise(PyObject *self, PyObject *args) {
    Py_buffer hb, ob;
    Py_ssize_t s, ny, nx;
    if (!PyArg_ParseTuple(args, "y*nnnw*", &hb, &s, &ny, &nx, &ob)) return NULL;
    PyObject *result = NULL;
    float *energy = NULL, *inv = NULL;
    if (!check_len(&hb, s * ny * nx * N_ORIENT, 4, "hist") || !check_len(&ob, s * ny * nx * 31, 4, "out")) goto done;
    if (ny < 1 || nx < 1) {
        PyErr_SetString(PyExc_ValueError, "hist: empty cell map");
        goto done;
    }
    const Py_ssize_t ew = nx + 2, iw = nx + 1;
    energy = PyMem_Malloc(sizeof(float) * (ny + 2) * ew);
    inv = PyMem_Malloc(sizeof(float) * (ny + 1) * iw);
    if (!energy || !inv) {
        PyErr_NoMemory();
        goto done;
    }
    const float *hist = hb.buf;
    float *out = ob.buf;
    const float clip = 0.2f, eps = 1e-4f, texture_scale = 0.2357f;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < s; k++) {
        const float *hk = hist + k * ny * nx * N_ORIENT;
        float *ok = out + k * ny * nx * 31;
        /* block energy of the contrast-insensitive histogram; the order of the sum is numpy's pairwise one for 9
         * terms, so the normalisers match it bit for bit */
        for (Py_ssize_t i = 0; i < ny; i++)
            for (Py_ssize_t j = 0; j < nx; j++) {
                const float *c = hk + (i * nx + j) * N_ORIENT;
                float q[9];
                for (int b = 0; b < 9; b++) {
                    float a = c[b] + c[b + 9];
                    q[b] = a * a;
                }
                energy[(i + 1) * ew + j + 1] = (((q[0] + q[1]) + (q[2] + q[3])) + ((q[4] + q[5]) + (q[6] + q[7]))) + q[8];
            }
        /* edge padding */
        for (Py_ssize_t j = 1; j <= nx; j++) {
            energy[j] = energy[ew + j];
            energy[(ny + 1) * ew + j] = energy[ny * ew + j];
        }
        for (Py_ssize_t i = 0; i < ny + 2; i++) {
            energy[i * ew] = energy[i * ew + 1];
            energy[i * ew + nx + 1] = energy[i * ew + nx];
        }
        for (Py_ssize_t i = 0; i <= ny; i++)
            for (Py_ssize_t j = 0; j <= nx; j++) {
                const float *e = energy + i * ew + j;
                float block = ((e[0] + e[ew]) + e[1]) + e[ew + 1];
                inv[i * iw + j] = 1.0f / sqrtf(block + eps);
            }
        for (Py_ssize_t i = 0; i < ny; i++)
            for (Py_ssize_t j = 0; j < nx; j++) {
                const float *c = hk + (i * nx + j) * N_ORIENT;
                float *o = ok + (i * nx + j) * 31;
                const float n[4] = {inv[i * iw + j], inv[i * iw + j + 1], inv[(i + 1) * iw + j], inv[(i + 1) * iw + j + 1]};
                float texture[4] = {0.0f, 0.0f, 0.0f, 0.0f};
                for (int b = 0; b < N_ORIENT; b++) {
                    float acc = 0.0f;
                    for (int corner = 0; corner < 4; corner++) {
                        float v = c[b] * n[corner];
                        if (v > clip) v = clip;
                        texture[corner] += v;
                        acc = corner == 0 ? v : acc + v;
                    }
                    o[b] = acc * 0.5f;
                }
                for (int b = 0; b < 9; b++) {
                    float a = c[b] + c[b + 9], acc = 0.0f;
                    for (int corner = 0; corner < 4; corner++) {
                        float v = a * n[corner];
                        if (v > clip) v = clip;
                        acc = corner == 0 ? v : acc + v;
                    }
                    o[N_ORIENT + b] = acc * 0.5f;
                }
                for (int corner = 0; corner < 4; corner++) o[27 + corner] = texture[corner] * texture_scale;
            }
    }
    Py_END_ALLOW_THREADS
    result = Py_None;
    Py_INCREF(result);
done:
    PyMem_Free(energy); PyMem_Free(inv);
    PyBuffer_Release(&hb); PyBuffer_Release(&ob);
    return result;
}

static PyMethodDef methods[] = {
    {"bilinear_cells", bilinear_cells, METH_VARARGS, "Bilinear reads of an (H, W, D) float32 map at S x ny x nx points."},
    {"tent_cells", tent_cells, METH_VARARGS, "Reads as bilinear_cells of the tent-blurred map, blurred only where read."},
    {"strongest_gradient", strongest_gradient, METH_VARARGS, "Per pixel, the gradient of the strongest of 3 channels."},
    {"orientation_votes", orientation_votes, METH_VARARGS, "Per-pixel votes into 18 orientation bins."},
    {"fhog_normalise", fhog_normalise, METH_VARARGS, "18-bin cell histograms -> 31 fHOG channels."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels", "Compiled inner loops of the ECO feature path.",
                                    -1, methods};

PyMODINIT_FUNC PyInit__kernels(void) { return PyModule_Create(&module); }
