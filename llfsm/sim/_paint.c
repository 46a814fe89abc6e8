/* llfsm.sim._paint: turtlesim's stroke painter (llfsm.sim.world._fill_stroke) in C.
 *
 * Why this exists: a colour sensor needs the path image up to date under the turtle after every
 * 16 ms update, so while anyone listens to <turtle>/color_sensor (a recorder, the web view, a
 * machine) every pen stroke is rasterised as it is drawn: about 2 us a stroke in Python, the
 * largest cost of such a run.  This is the same rasteriser, the same floating-point operations
 * in the same order (compiled without contraction into fused multiply-adds, see setup.py), and
 * the length from Python's own math.hypot, so it paints exactly the pixels the Python one
 * paints (tests/test_sim.py checks both against the reference painter).
 *
 * fill_stroke(buf, x0, y0, x1, y1, rgba, width) -> bool: False, having painted nothing, where
 * anything is not the ordinary case (not a 500 x 500 RGBA bytearray, not floats, a rounding of
 * an infinity or NaN); the caller then uses the Python painter, which does what it always did.
 *
 * Nothing borrowed is kept across the one call that runs Python code (math.hypot, which is
 * whatever `math.hypot` was when this module was imported): the image's size is checked again
 * after it, and the image's memory is taken only then.  It needs the GIL (setup.py skips it on
 * free-threaded CPython: another thread could resize the image while it paints).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#ifdef Py_GIL_DISABLED
#error "llfsm.sim._paint needs the GIL: free-threaded CPython is not supported (setup.py skips it there)"
#endif
#include <math.h>
#include <string.h>

#define CANVAS_PX 500

static PyObject *hypot_fn; /* math.hypot */

/* Python's math.hypot(dx, dy): not libm's, whose last bit may differ. */
static int py_hypot(double dx, double dy, double *out) {
    PyObject *args[2] = {PyFloat_FromDouble(dx), PyFloat_FromDouble(dy)};
    PyObject *r = NULL;
    if (args[0] && args[1]) r = PyObject_Vectorcall(hypot_fn, args, 2, NULL);
    Py_XDECREF(args[0]);
    Py_XDECREF(args[1]);
    if (r == NULL) return -1;
    *out = PyFloat_AsDouble(r);
    Py_DECREF(r);
    return (*out == -1.0 && PyErr_Occurred()) ? -1 : 0;
}

/* max(0, ceil(v)) and min(CANVAS_PX - 1, ceil(v) - 1) as the Python painter has them, for a
 * finite v, held within -1..CANVAS_PX (beyond, a span is empty all the same) so that the
 * conversion to long cannot overflow. */
static long first_index(double v) {
    double f = ceil(v);
    return f < 0 ? 0 : (f > CANVAS_PX ? CANVAS_PX : (long)f);
}

static long last_index(double v) {
    double f = ceil(v) - 1;
    return f > CANVAS_PX - 1 ? CANVAS_PX - 1 : (f < -1 ? -1 : (long)f);
}

static PyObject *fill_stroke(PyObject *module, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 7) {
        PyErr_SetString(PyExc_TypeError, "fill_stroke(buf, x0, y0, x1, y1, rgba, width)");
        return NULL;
    }
    PyObject *buf = args[0], *rgba = args[5], *w = args[6];
    if (!PyByteArray_CheckExact(buf) || PyByteArray_GET_SIZE(buf) != CANVAS_PX * CANVAS_PX * 4
        || !PyBytes_CheckExact(rgba) || PyBytes_GET_SIZE(rgba) != 4 || !PyLong_CheckExact(w))
        Py_RETURN_FALSE;
    for (int i = 1; i < 5; i++)
        if (!PyFloat_CheckExact(args[i])) Py_RETURN_FALSE;
    double x0 = PyFloat_AS_DOUBLE(args[1]), y0 = PyFloat_AS_DOUBLE(args[2]);
    double x1 = PyFloat_AS_DOUBLE(args[3]), y1 = PyFloat_AS_DOUBLE(args[4]);
    if (!(isfinite(x0) && isfinite(y0) && isfinite(x1) && isfinite(y1))) Py_RETURN_TRUE; /* paints nothing */
    long width = PyLong_AsLong(w);
    if (width == -1 && PyErr_Occurred()) {
        PyErr_Clear();
        Py_RETURN_FALSE;
    }
    if (width < 0 || width > (1L << 30)) Py_RETURN_FALSE;

    double half = (double)width / 2.0;
    double dx = x1 - x0, dy = y1 - y0, length;
    if (py_hypot(dx, dy, &length) < 0) {
        PyErr_Clear();
        Py_RETURN_FALSE;
    }
    double ux, uy;
    if (length > 0.0) {
        ux = dx / length;
        uy = dy / length;
    } else {
        ux = 1.0;
        uy = 0.0;
    }
    double cx = (x0 + x1) / 2.0, cy = (y0 + y1) / 2.0;
    double along = length / 2.0 + half;
    double ey = fabs(uy) * along + fabs(ux) * half;
    double top = cy - ey - 0.5, bottom = cy + ey - 0.5;
    if (!isfinite(top) || !isfinite(bottom)) Py_RETURN_FALSE; /* math.ceil would raise */
    long j0 = first_index(top), j1 = last_index(bottom);

    /* Every row's span first, painting nothing until all are known to be ordinary. */
    long spans[CANVAS_PX][2];
    long rows = 0;
    for (long j = j0; j <= j1; j++) {
        double d = (double)j + 0.5 - cy;
        double xl = -INFINITY, xr = INFINITY, a, b;
        if (ux != 0.0) {
            a = (-along - d * uy) / ux;
            b = (along - d * uy) / ux;
            if (a > b) {
                double t = a;
                a = b;
                b = t;
            }
            xl = a;
            xr = b;
        } else if (fabs(d * uy) > along) {
            continue;
        }
        if (uy != 0.0) {
            a = (half - d * ux) / -uy;
            b = (-half - d * ux) / -uy;
            if (a > b) {
                double t = a;
                a = b;
                b = t;
            }
            if (a > xl) xl = a;
            if (b < xr) xr = b;
        } else if (fabs(d * ux) > half) {
            continue;
        }
        double left = cx + xl - 0.5, right = cx + xr - 0.5;
        if (!isfinite(left) || !isfinite(right)) Py_RETURN_FALSE;
        long i0 = first_index(left), i1 = last_index(right);
        if (i0 <= i1) {
            spans[rows][0] = j * CANVAS_PX + i0;
            spans[rows][1] = i1 - i0 + 1;
            rows++;
        }
    }
    if (PyByteArray_GET_SIZE(buf) != CANVAS_PX * CANVAS_PX * 4) Py_RETURN_FALSE; /* resized meanwhile */
    unsigned char *pixels = (unsigned char *)PyByteArray_AS_STRING(buf);
    const unsigned char *colour = (const unsigned char *)PyBytes_AS_STRING(rgba);
    for (long r = 0; r < rows; r++) {
        unsigned char *p = pixels + spans[r][0] * 4;
        for (long k = 0; k < spans[r][1]; k++, p += 4) memcpy(p, colour, 4);
    }
    Py_RETURN_TRUE;
}

static PyMethodDef methods[] = {
    {"fill_stroke", (PyCFunction)(void (*)(void))fill_stroke, METH_FASTCALL,
     "fill_stroke(buf, x0, y0, x1, y1, rgba, width) -> bool: paint one pen stroke as "
     "llfsm.sim.world._fill_stroke does; False (nothing painted) to leave it to that function."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef paintmodule = {
    PyModuleDef_HEAD_INIT,
    .m_name = "llfsm.sim._paint",
    .m_doc = "turtlesim's stroke painter in C (see _paint.c).",
    .m_size = -1,
    .m_methods = methods,
};

PyMODINIT_FUNC PyInit__paint(void) {
    /* LLFSM_NO_C=1: the import fails and llfsm.sim.world paints in Python (as llfsm.bag._tap) */
    const char *no_c = getenv("LLFSM_NO_C");
    if (no_c != NULL && no_c[0] != '\0' && strcmp(no_c, "0") != 0) {
        PyErr_SetString(PyExc_ImportError, "llfsm.sim._paint is disabled by LLFSM_NO_C");
        return NULL;
    }
    PyObject *math = PyImport_ImportModule("math");
    if (math == NULL) return NULL;
    hypot_fn = PyObject_GetAttrString(math, "hypot");
    Py_DECREF(math);
    if (hypot_fn == NULL) return NULL;
    return PyModule_Create(&paintmodule);
}
