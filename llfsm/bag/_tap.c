/* llfsm.bag._tap: the recorder's tap for a message of a fixed size, and its buffer, in C.
 *
 * Why this exists: under --record every published message is appended to the recorder's
 * buffer as one pipe record (uint32 key, int64 clock.now, uint32 size, the CDR with its
 * encapsulation header).  The generated Python function `_stamped_<Name>` does it in one
 * struct.pack, but on a busy bus that call is most of what recording costs a round (about
 * 0.2 us a message beside ~0.17 us per machine ringlet).  A Tap does the same work in one C
 * call: it reads the message's slots directly (at the offsets of the member descriptors of
 * the exact classes it saw first, where reading the slot is what Python's attribute access
 * would do: see `resolve`), packs as struct.pack does (the same integer ranges, the same float
 * rounding) and appends to a Spool, which keeps its memory between batches.
 *
 * It never decides a message is wrong: whenever anything is not as expected (another class at
 * some level, an unset slot, a value struct.pack would refuse or convert some other way), it
 * calls the generated Python function instead, which appends the same bytes or raises what it
 * always raised.  A record is appended whole or not at all.
 *
 * A Tap is made from the `layout` of the message's Codec (llfsm/idl/ddsgen.py writes it):
 * one (format, path) pair per struct item of the CDR after its header, for example
 * ("d", "_linear._x"), ("36d", "*_covariance") or ("3x", "").
 *
 * One rule for everything below: nothing borrowed (a pointer into an object, a size, the tap's
 * own fields) is kept across a call that can run Python code (clock.now, a fallback, a
 * destructor), since that code may change or free it.  The only such call in the fast path is
 * clock.now; a call holds its own references to what it uses, and reserves and writes its
 * record after clock.now, running no Python code in between.
 *
 * It needs CPython's full C API (member descriptors, type version tags, _PyType_Lookup: not in
 * the limited API) and the GIL (setup.py says why, and skips it on free-threaded builds).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#ifdef Py_GIL_DISABLED
#error "llfsm.bag._tap needs the GIL: free-threaded CPython is not supported (setup.py skips it there)"
#endif
#include <stdint.h>
#include <math.h>
#include <string.h>

#define HEAD 16 /* uint32 key, int64 time, uint32 size */
static const unsigned char CDR_LE[4] = {0, 1, 0, 0}; /* encapsulation: CDR, little endian */

/* The recorder's buffer of pipe records: appended to by the taps (and the Python code for
 * messages of varying size) in the run's thread, taken whole by the recorder's sending thread
 * (both under the GIL).  Unlike a bytearray it keeps its memory between batches, so the pages
 * are not faulted in again each time, and a batch leaves it in one copy. */
typedef struct {
    PyObject_HEAD
    char *data;
    Py_ssize_t len, cap;
} SpoolObject;

static PyTypeObject SpoolType;

/* Room for `n` more bytes at data + len; -1 with MemoryError set. */
static int spool_reserve(SpoolObject *s, Py_ssize_t n) {
    if (s->cap - s->len >= n) return 0;
    if (n > PY_SSIZE_T_MAX / 2 - s->len) {
        PyErr_NoMemory();
        return -1;
    }
    Py_ssize_t cap = s->cap ? s->cap : 1 << 16;
    while (cap - s->len < n) cap *= 2;
    char *data = PyMem_Realloc(s->data, (size_t)cap);
    if (data == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    s->data = data;
    s->cap = cap;
    return 0;
}

static PyObject *spool_extend(SpoolObject *s, PyObject *arg) {
    Py_buffer view;
    if (PyObject_GetBuffer(arg, &view, PyBUF_SIMPLE) < 0) return NULL;
    if (spool_reserve(s, view.len) < 0) {
        PyBuffer_Release(&view);
        return NULL;
    }
    if (view.len > 0) { /* (a fresh spool has no memory yet) */
        memcpy(s->data + s->len, view.buf, (size_t)view.len);
        s->len += view.len;
    }
    PyBuffer_Release(&view);
    Py_RETURN_NONE;
}

static PyObject *spool_take(SpoolObject *s, PyObject *Py_UNUSED(ignored)) {
    PyObject *batch = PyBytes_FromStringAndSize(s->data, s->len);
    if (batch == NULL) return NULL;
    s->len = 0;
    if (s->cap > (1 << 23) && PyBytes_GET_SIZE(batch) < s->cap / 4) { /* a burst is over: give half back */
        char *data = PyMem_Realloc(s->data, (size_t)(s->cap / 2));
        if (data != NULL) {
            s->data = data;
            s->cap /= 2;
        }
    }
    return batch;
}

static Py_ssize_t spool_length(SpoolObject *s) { return s->len; }

static void spool_dealloc(SpoolObject *s) {
    PyMem_Free(s->data);
    Py_TYPE(s)->tp_free((PyObject *)s);
}

static PyMethodDef spool_methods[] = {
    {"extend", (PyCFunction)spool_extend, METH_O, "Append the bytes of a bytes-like object."},
    {"take", (PyCFunction)spool_take, METH_NOARGS, "Everything waiting, as bytes, leaving the spool empty."},
    {NULL},
};

static PySequenceMethods spool_as_sequence = {.sq_length = (lenfunc)spool_length};

static PyTypeObject SpoolType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "llfsm.bag._tap.Spool",
    .tp_doc = PyDoc_STR("Spool(): the recorder's buffer of pipe records (extend, take, len)."),
    .tp_basicsize = sizeof(SpoolObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = PyType_GenericNew,
    .tp_dealloc = (destructor)spool_dealloc,
    .tp_methods = spool_methods,
    .tp_as_sequence = &spool_as_sequence,
};

typedef struct {
    char code;            /* one of ? b B h H i I q Q f d x */
    Py_ssize_t count;     /* items of that code */
    int starred;          /* the value is a list or tuple of `count` items */
    Py_ssize_t hops;      /* attribute names from the message to the value */
    PyObject **names;     /* interned str, owned */
    PyTypeObject **types; /* the class seen at each hop when resolved, owned */
    unsigned int *versions; /* its tp_version_tag then: any change to the class (or a base) changes it */
    Py_ssize_t *offsets;  /* its slot's offset */
} Item;

/* A tap's layout: its items and the CDR size they make.  Tap.__init__ builds a new one aside and
 * swaps it in only when it is whole; nothing changes it after that but what `resolve` learns
 * (classes and offsets, each hop's three written together).  A call holds a reference to the
 * layout it started with, whatever Python code it runs meanwhile (clock.now) does to the tap. */
typedef struct {
    PyObject_HEAD
    uint32_t size;      /* CDR size, header included */
    Py_ssize_t nitems;
    Item *items;
    int resolved;       /* 0 not yet, 1 yes, -1 never (always the fallback) */
} LayoutObject;

static PyTypeObject LayoutType;

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    SpoolObject *out;   /* the recorder's spool */
    PyObject *clock;    /* anything with an int `now` */
    PyObject *fallback; /* the generated Python tap: same bytes, or the error */
    LayoutObject *layout; /* NULL until __init__ succeeds */
    uint32_t key;
    unsigned long long fallbacks; /* calls handed to the fallback (tests read it) */
} TapObject;

static PyObject *str_now;

static Py_ssize_t item_width(char code) {
    switch (code) {
    case '?': case 'b': case 'B': case 'x': return 1;
    case 'h': case 'H': return 2;
    case 'i': case 'I': case 'f': return 4;
    case 'q': case 'Q': case 'd': return 8;
    default: return -1;
    }
}

static void put_u32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static void put_u64(unsigned char *p, uint64_t v) {
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* One value in little-endian order, as struct.pack("<" + code) writes it; -1 (no Python
 * error left set) where struct.pack would raise or where the value is not a plain int or
 * float (the fallback then does exactly what struct.pack does with it). */
static int put_value(char code, PyObject *v, unsigned char *p) {
    if (code == 'd' || code == 'f') {
        double x;
        if (PyFloat_CheckExact(v))
            x = PyFloat_AS_DOUBLE(v);
        else if (PyLong_CheckExact(v)) {
            x = PyLong_AsDouble(v);
            if (x == -1.0 && PyErr_Occurred()) goto error;
        } else
            return -1;
#if PY_LITTLE_ENDIAN
        /* what PyFloat_Pack8/4(x, p, 1) do on a little-endian IEEE machine, without the calls */
        if (code == 'd') {
            memcpy(p, &x, 8);
        } else {
            float y = (float)x;
            if (isinf(y) && !isinf(x)) return -1; /* struct: "float too large to pack with f format" */
            memcpy(p, &y, 4);
        }
#else
        if ((code == 'd' ? PyFloat_Pack8(x, (char *)p, 1) : PyFloat_Pack4(x, (char *)p, 1)) < 0) goto error;
#endif
        return 0;
    }
    if (code == '?') {
        if (v == Py_True) *p = 1;
        else if (v == Py_False) *p = 0;
        else return -1;
        return 0;
    }
    if (!PyLong_CheckExact(v)) return -1;
    int overflow = 0;
    long long s = PyLong_AsLongLongAndOverflow(v, &overflow);
    if (s == -1 && PyErr_Occurred()) goto error;
    if (overflow > 0 && code == 'Q') {
        unsigned long long u = PyLong_AsUnsignedLongLong(v);
        if (u == (unsigned long long)-1 && PyErr_Occurred()) goto error;
        put_u64(p, u);
        return 0;
    }
    if (overflow) return -1;
    switch (code) {
    case 'b': if (s < -128 || s > 127) return -1; *p = (unsigned char)(int8_t)s; return 0;
    case 'B': if (s < 0 || s > 255) return -1; *p = (unsigned char)s; return 0;
    case 'h': if (s < -32768 || s > 32767) return -1; p[0] = (unsigned char)s; p[1] = (unsigned char)((uint16_t)s >> 8); return 0;
    case 'H': if (s < 0 || s > 65535) return -1; p[0] = (unsigned char)s; p[1] = (unsigned char)(s >> 8); return 0;
    case 'i': if (s < INT32_MIN || s > INT32_MAX) return -1; put_u32(p, (uint32_t)(int32_t)s); return 0;
    case 'I': if (s < 0 || s > UINT32_MAX) return -1; put_u32(p, (uint32_t)s); return 0;
    case 'q': put_u64(p, (uint64_t)s); return 0;
    case 'Q': if (s < 0) return -1; put_u64(p, (uint64_t)s); return 0;
    default: return -1;
    }
error:
    PyErr_Clear();
    return -1;
}

/* The object at the end of an item's path, borrowed: 0; -1 if some level is not the class it
 * was (the fallback's case); -2 if that class has changed since it was resolved (resolve again).
 * Runs no Python code, so nothing can free what it hands back before the caller has packed it. */
static int walk(const Item *it, PyObject *m, PyObject **v) {
    PyObject *o = m;
    for (Py_ssize_t j = 0; j < it->hops; j++) {
        PyTypeObject *t = it->types[j];
        if (Py_TYPE(o) != t) return -1; /* (never NULL: an unresolved hop never matches) */
        if (t->tp_version_tag != it->versions[j]) return -2;
        o = *(PyObject **)((char *)o + it->offsets[j]);
        if (o == NULL) return -1;
    }
    *v = o;
    return 0;
}

/* 1 if every name in the class dicts of t's MRO is an exact str: looking a name up there then
 * compares strings only and never runs Python code (a str subclass's __eq__ or an object's
 * __hash__ could, and change the class under the lookup). */
static int plain_dicts(PyTypeObject *t) {
    PyObject *mro = t->tp_mro;
    if (mro == NULL || !PyTuple_Check(mro)) return 0;
    for (Py_ssize_t i = 0; i < PyTuple_GET_SIZE(mro); i++) {
        PyObject *base = PyTuple_GET_ITEM(mro, i);
        if (!PyType_Check(base)) return 0;
        PyObject *dict = ((PyTypeObject *)base)->tp_dict, *key, *value;
        if (dict == NULL || !PyDict_CheckExact(dict)) return 0;
        Py_ssize_t pos = 0;
        while (PyDict_Next(dict, &pos, &key, &value))
            if (!PyUnicode_CheckExact(key)) return 0;
    }
    return 1;
}

/* The classes a layout stopped referring to during one call, released when the call is done.
 * A class is kept alive by cycles of its own (its __mro__), so this is caution more than need:
 * but a Py_DECREF that frees something runs Python code (weak references' callbacks), and no
 * Python code may run while the call holds borrowed pointers or a reserved record. */
typedef struct {
    PyObject **items;
    Py_ssize_t n, cap;
} Retired;

static int retire(Retired *r, PyObject *o) {
    if (o == NULL) return 0;
    if (r->n == r->cap) {
        Py_ssize_t cap = r->cap ? 2 * r->cap : 8;
        PyObject **items = PyMem_Realloc(r->items, (size_t)cap * sizeof(PyObject *));
        if (items == NULL) return -1;
        r->items = items;
        r->cap = cap;
    }
    r->items[r->n++] = o;
    return 0;
}

static void release(Retired *r) {
    for (Py_ssize_t i = 0; i < r->n; i++) Py_DECREF(r->items[i]);
    PyMem_Free(r->items);
}

/* Learn each hop's class and slot offset from this message: 0, or -1 if at some hop the tap
 * cannot read what `o.name` gives in Python (then this layout always falls back).  A hop is
 * read in C only where Python's attribute access would come down to reading that very slot:
 * the class looks attributes up the ordinary way (no __getattribute__ or __getattr__), `name`
 * found on it (first in its MRO) is a member descriptor for an object slot, and that
 * descriptor belongs to the class itself.  A generated message class declares its own slots,
 * so it passes; a subclass passes only by declaring the slot again itself, and anything else
 * (a slot descriptor of another class, which would make the offset point into some other
 * layout; a property; a plain class attribute; an inherited slot) goes to the Python tap.
 * Runs no Python code (see plain_dicts; the classes it stops referring to go to `retired`)
 * and sets no error. */
static int resolve(LayoutObject *layout, PyObject *m, Retired *retired) {
    for (Py_ssize_t i = 0; i < layout->nitems; i++) {
        Item *it = &layout->items[i];
        PyObject *o = m;
        for (Py_ssize_t j = 0; j < it->hops; j++) {
            PyTypeObject *t = Py_TYPE(o);
            if (t->tp_getattro != PyObject_GenericGetAttr || !plain_dicts(t)) return -1;
            PyObject *d = _PyType_Lookup(t, it->names[j]); /* borrowed; assigns t a version tag */
            if (d == NULL || !Py_IS_TYPE(d, &PyMemberDescr_Type)) return -1;
            PyMemberDef *member = ((PyMemberDescrObject *)d)->d_member;
            if (PyDescr_TYPE(d) != t || member->type != T_OBJECT_EX || (member->flags & PY_AUDIT_READ)) return -1;
            if (t->tp_version_tag == 0) return -1; /* no tag to tell a later change by */
            if (it->types[j] != t) { /* (the hop's class, version and offset change together) */
                if (retire(retired, (PyObject *)it->types[j]) < 0) return -1;
                Py_INCREF(t);
                it->types[j] = t;
            }
            it->versions[j] = t->tp_version_tag;
            it->offsets[j] = member->offset;
            o = *(PyObject **)((char *)o + member->offset);
            if (o == NULL) return -1;
        }
    }
    return 0;
}

/* Pack the CDR body into p: 0; -1 to fall back; -2 if a class has changed since it was resolved.
 * Runs no Python code and sets no error. */
static int pack_body(LayoutObject *layout, PyObject *m, unsigned char *p) {
    for (Py_ssize_t i = 0; i < layout->nitems; i++) {
        const Item *it = &layout->items[i];
        Py_ssize_t w = item_width(it->code);
        if (it->code == 'x') {
            memset(p, 0, (size_t)it->count);
            p += it->count;
            continue;
        }
        PyObject *v;
        int got = walk(it, m, &v);
        if (got < 0) return got;
        if (!it->starred) {
            if (put_value(it->code, v, p) < 0) return -1;
            p += w;
            continue;
        }
        if (it->code == 'B' && PyBytes_CheckExact(v)) {
            if (PyBytes_GET_SIZE(v) != it->count) return -1;
            memcpy(p, PyBytes_AS_STRING(v), (size_t)it->count);
            p += it->count;
            continue;
        }
        if (!PyList_CheckExact(v) && !PyTuple_CheckExact(v)) return -1;
        if (PySequence_Fast_GET_SIZE(v) != it->count) return -1;
        PyObject **vs = PySequence_Fast_ITEMS(v);
        for (Py_ssize_t k = 0; k < it->count; k++, p += w)
            if (put_value(it->code, vs[k], p) < 0) return -1;
    }
    return 0;
}

/* clock.now as an int64: 1; 0 (no error set) if it is not an int that fits; -1 if reading it
 * raised.  Runs Python code (a property, __getattr__, a destructor...). */
static int read_now(PyObject *clock, long long *t) {
    PyObject *now = PyObject_GetAttr(clock, str_now);
    if (now == NULL) return -1;
    int overflow = 0;
    *t = PyLong_Check(now) ? PyLong_AsLongLongAndOverflow(now, &overflow) : 0;
    int fits = PyLong_Check(now) && !overflow && !(*t == -1 && PyErr_Occurred());
    Py_DECREF(now);
    PyErr_Clear();
    return fits;
}

/* One call, with what the tap held when it began (owned by the caller for the whole call). */
static PyObject *tap_record(TapObject *self, LayoutObject *layout, SpoolObject *out, PyObject *clock,
                            PyObject *fallback, uint32_t key, PyObject *m) {
    Retired retired = {NULL, 0, 0};
    PyObject *result = NULL;
    if (layout->resolved == 0) layout->resolved = resolve(layout, m, &retired) == 0 ? 1 : -1;
    if (layout->resolved < 0) goto fall_back;
    long long t;
    int got = read_now(clock, &t); /* Python code: from here on, nothing borrowed from before */
    if (got < 0) goto done;
    if (got == 0) goto fall_back;
    Py_ssize_t total = HEAD + layout->size;
    if (spool_reserve(out, total) < 0) goto done;
    /* From the reservation to the commit no Python code runs: p stays valid, and the record is
     * appended whole or not at all. */
    unsigned char *p = (unsigned char *)out->data + out->len;
    int packed = pack_body(layout, m, p + HEAD + 4);
    if (packed == -2) { /* a class changed (an attribute set on it, say): learn it again */
        layout->resolved = resolve(layout, m, &retired) == 0 ? 1 : -1;
        packed = layout->resolved > 0 ? pack_body(layout, m, p + HEAD + 4) : -1;
    }
    if (packed < 0) goto fall_back;
    put_u32(p, key);
    put_u64(p + 4, (uint64_t)t);
    put_u32(p + 12, layout->size);
    memcpy(p + HEAD, CDR_LE, 4);
    out->len += total;
    result = Py_NewRef(Py_None);
    goto done;
fall_back:
    self->fallbacks++;
    result = PyObject_CallOneArg(fallback, m);
done:
    release(&retired);
    return result;
}

static PyObject *tap_vectorcall(PyObject *callable, PyObject *const *args, size_t nargsf, PyObject *kwnames) {
    TapObject *self = (TapObject *)callable;
    if (PyVectorcall_NARGS(nargsf) != 1 || kwnames != NULL) {
        PyErr_SetString(PyExc_TypeError, "a tap takes one message");
        return NULL;
    }
    if (self->layout == NULL) {
        PyErr_SetString(PyExc_TypeError, "this Tap was never initialised");
        return NULL;
    }
    /* Held for the whole call: clock.now runs Python code, which may re-initialise this tap or
     * drop the last other reference to any of these. */
    LayoutObject *layout = self->layout;
    SpoolObject *out = self->out;
    PyObject *clock = self->clock, *fallback = self->fallback;
    Py_INCREF(layout);
    Py_INCREF(out);
    Py_INCREF(clock);
    Py_INCREF(fallback);
    PyObject *result = tap_record(self, layout, out, clock, fallback, self->key, args[0]);
    Py_DECREF(layout);
    Py_DECREF(out);
    Py_DECREF(clock);
    Py_DECREF(fallback);
    return result;
}

static void free_items(Item *items, Py_ssize_t n) {
    if (items == NULL) return;
    for (Py_ssize_t i = 0; i < n; i++) {
        Item *it = &items[i];
        for (Py_ssize_t j = 0; j < it->hops; j++) {
            if (it->names) Py_XDECREF(it->names[j]);
            if (it->types) Py_XDECREF(it->types[j]);
        }
        PyMem_Free(it->names);
        PyMem_Free(it->types);
        PyMem_Free(it->versions);
        PyMem_Free(it->offsets);
    }
    PyMem_Free(items);
}

static int split_path(const char *path, Item *it) {
    Py_ssize_t hops = 0;
    if (path[0] != '\0') {
        hops = 1;
        for (const char *c = path; *c; c++) hops += *c == '.';
    }
    size_t n = (size_t)(hops ? hops : 1);
    it->names = PyMem_Calloc(n, sizeof(PyObject *));
    it->types = PyMem_Calloc(n, sizeof(PyTypeObject *));
    it->versions = PyMem_Calloc(n, sizeof(unsigned int));
    it->offsets = PyMem_Calloc(n, sizeof(Py_ssize_t));
    if (!it->names || !it->types || !it->versions || !it->offsets) {
        PyErr_NoMemory();
        return -1;
    }
    const char *start = path;
    for (Py_ssize_t j = 0; j < hops; j++) {
        const char *end = strchr(start, '.');
        Py_ssize_t len = end ? end - start : (Py_ssize_t)strlen(start);
        if (len == 0) {
            PyErr_Format(PyExc_ValueError, "a tap item's path has an empty name: %s", path);
            return -1;
        }
        PyObject *name = PyUnicode_FromStringAndSize(start, len);
        if (name == NULL) return -1;
        PyUnicode_InternInPlace(&name);
        it->names[j] = name;
        it->hops = j + 1; /* what free_items releases, should a later name fail */
        start = end ? end + 1 : start + len;
    }
    return 0;
}

/* One ("36d", "*_covariance") pair of a layout into `it`: the bytes it packs, or -1 with
 * TypeError/ValueError set. */
static Py_ssize_t parse_item(PyObject *pair, Item *it) {
    const char *fmt, *path;
    if (!PyTuple_Check(pair) || !PyArg_ParseTuple(pair, "ss", &fmt, &path)) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "a tap item is a (format, path) tuple");
        return -1;
    }
    Py_ssize_t count = 0;
    const char *c = fmt;
    for (; *c >= '0' && *c <= '9' && count <= (1 << 20); c++) count = count * 10 + (*c - '0');
    if (c == fmt) count = 1;
    if (count < 1 || count > (1 << 20) || item_width(c[0]) < 0 || c[1] != '\0') {
        PyErr_Format(PyExc_ValueError, "a tap item's format must be [count]code: %s", fmt);
        return -1;
    }
    it->code = c[0];
    it->count = count;
    it->starred = path[0] == '*';
    if (it->starred) path++;
    if ((it->code == 'x') != (path[0] == '\0') || (it->code == 'x' && it->starred)
        || (count > 1 && it->code != 'x' && !it->starred)) {
        PyErr_Format(PyExc_ValueError, "a tap item's path does not fit its format %s: %s", fmt, path);
        return -1;
    }
    if (split_path(path, it) < 0) return -1;
    return count * item_width(it->code);
}

/* A whole new layout from a tuple of (format, path) pairs, or NULL with the error set. */
static LayoutObject *layout_from(PyObject *pairs) {
    LayoutObject *layout = PyObject_GC_New(LayoutObject, &LayoutType);
    if (layout == NULL) return NULL;
    Py_ssize_t n = PyTuple_GET_SIZE(pairs);
    layout->size = 0;
    layout->resolved = 0;
    layout->nitems = n;
    layout->items = PyMem_Calloc((size_t)(n ? n : 1), sizeof(Item));
    PyObject_GC_Track(layout);
    if (layout->items == NULL) {
        Py_DECREF(layout);
        return (LayoutObject *)PyErr_NoMemory();
    }
    Py_ssize_t body = 0;
    for (Py_ssize_t i = 0; i < n; i++) {
        Py_ssize_t bytes = parse_item(PyTuple_GET_ITEM(pairs, i), &layout->items[i]);
        if (bytes < 0) {
            Py_DECREF(layout);
            return NULL;
        }
        body += bytes; /* at most 2**20 items of 8 bytes each: no overflow before the check below */
        if (body > (1 << 24)) {
            PyErr_SetString(PyExc_ValueError, "a tap's layout is larger than 16 MiB");
            Py_DECREF(layout);
            return NULL;
        }
    }
    layout->size = (uint32_t)(4 + body);
    return layout;
}

static int layout_traverse(LayoutObject *self, visitproc visit, void *arg) {
    for (Py_ssize_t i = 0; self->items && i < self->nitems; i++)
        for (Py_ssize_t j = 0; j < self->items[i].hops; j++)
            Py_VISIT((PyObject *)self->items[i].types[j]);
    return 0;
}

static int layout_clear(LayoutObject *self) {
    for (Py_ssize_t i = 0; self->items && i < self->nitems; i++)
        for (Py_ssize_t j = 0; j < self->items[i].hops; j++)
            Py_CLEAR(self->items[i].types[j]); /* walk then never matches: a NULL class */
    return 0;
}

static void layout_dealloc(LayoutObject *self) {
    PyObject_GC_UnTrack(self);
    free_items(self->items, self->nitems);
    PyObject_GC_Del(self);
}

static PyTypeObject LayoutType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "llfsm.bag._tap._Layout",
    .tp_basicsize = sizeof(LayoutObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_dealloc = (destructor)layout_dealloc,
    .tp_traverse = (traverseproc)layout_traverse,
    .tp_clear = (inquiry)layout_clear,
};

static int tap_init(TapObject *self, PyObject *args, PyObject *kwds) {
    static char *kwlist[] = {"out", "key", "clock", "layout", "fallback", NULL};
    PyObject *out, *key_obj, *clock, *pairs, *fallback;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O!O!OO!O:Tap", kwlist, &SpoolType, &out, &PyLong_Type, &key_obj,
                                     &clock, &PyTuple_Type, &pairs, &fallback))
        return -1;
    unsigned long key = PyLong_AsUnsignedLong(key_obj); /* (not "k", which wraps 2**64 round to 0) */
    if ((key == (unsigned long)-1 && PyErr_Occurred()) || key > UINT32_MAX || !PyCallable_Check(fallback)) {
        PyErr_Clear();
        PyErr_SetString(PyExc_ValueError, "Tap(out, key < 2**32, clock, layout, fallback: a callable)");
        return -1;
    }
    /* Built aside: a layout that fails leaves the tap as it was (and a call in progress, which
     * holds its own references, goes on with what it began with). */
    LayoutObject *layout = layout_from(pairs);
    if (layout == NULL) return -1;
    /* Everything swapped in before anything old is released: a destructor that runs when the
     * old clock goes may call this tap, and finds it whole. */
    LayoutObject *old_layout = self->layout;
    SpoolObject *old_out = self->out;
    PyObject *old_clock = self->clock, *old_fallback = self->fallback;
    Py_INCREF(out);
    Py_INCREF(clock);
    Py_INCREF(fallback);
    self->layout = layout;
    self->out = (SpoolObject *)out;
    self->clock = clock;
    self->fallback = fallback;
    self->key = (uint32_t)key;
    self->vectorcall = tap_vectorcall;
    Py_XDECREF(old_layout);
    Py_XDECREF(old_out);
    Py_XDECREF(old_clock);
    Py_XDECREF(old_fallback);
    return 0;
}

static int tap_traverse(TapObject *self, visitproc visit, void *arg) {
    Py_VISIT((PyObject *)self->out);
    Py_VISIT(self->clock);
    Py_VISIT(self->fallback);
    Py_VISIT((PyObject *)self->layout);
    return 0;
}

static int tap_clear(TapObject *self) {
    Py_CLEAR(self->layout);
    Py_CLEAR(self->out);
    Py_CLEAR(self->clock);
    Py_CLEAR(self->fallback);
    return 0;
}

static void tap_dealloc(TapObject *self) {
    PyObject_GC_UnTrack(self);
    tap_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *tap_get_fallbacks(TapObject *self, void *closure) {
    return PyLong_FromUnsignedLongLong(self->fallbacks);
}

static PyGetSetDef tap_getset[] = {
    {"fallbacks", (getter)tap_get_fallbacks, NULL, "calls handed to the Python tap", NULL},
    {NULL},
};

static PyTypeObject TapType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "llfsm.bag._tap.Tap",
    .tp_doc = PyDoc_STR("Tap(out, key, clock, layout, fallback): appends a fixed-size message's pipe record "
                        "to the Spool `out`, as the generated _stamped_<Name> does."),
    .tp_basicsize = sizeof(TapObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)tap_init,
    .tp_dealloc = (destructor)tap_dealloc,
    .tp_traverse = (traverseproc)tap_traverse,
    .tp_clear = (inquiry)tap_clear,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(TapObject, vectorcall),
    .tp_getset = tap_getset,
};

static struct PyModuleDef tapmodule = {
    PyModuleDef_HEAD_INIT,
    .m_name = "llfsm.bag._tap",
    .m_doc = "The recorder's tap for fixed-size messages, in C (see _tap.c).",
    .m_size = -1,
};

PyMODINIT_FUNC PyInit__tap(void) {
    /* LLFSM_NO_C=1: the import fails, so every place that imports this module takes the Python
     * code it falls back to where the module is not built (tests run that way too).  Read here,
     * where every import passes, rather than at each import site. */
    const char *no_c = getenv("LLFSM_NO_C");
    if (no_c != NULL && no_c[0] != '\0' && strcmp(no_c, "0") != 0) {
        PyErr_SetString(PyExc_ImportError, "llfsm.bag._tap is disabled by LLFSM_NO_C");
        return NULL;
    }
    str_now = PyUnicode_InternFromString("now");
    if (str_now == NULL || PyType_Ready(&TapType) < 0 || PyType_Ready(&SpoolType) < 0
        || PyType_Ready(&LayoutType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&tapmodule);
    if (m == NULL) return NULL;
    Py_INCREF(&TapType);
    if (PyModule_AddObject(m, "Tap", (PyObject *)&TapType) < 0) {
        Py_DECREF(&TapType);
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(&SpoolType);
    if (PyModule_AddObject(m, "Spool", (PyObject *)&SpoolType) < 0) {
        Py_DECREF(&SpoolType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
