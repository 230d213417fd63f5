"""fractalbake in Python: bakes in-process through libfractalbake, channels as numpy arrays.

    import fractalbake
    planes = fractalbake.render()                       # the embedded default scene
    sky = fractalbake.render("sky.json", size=(512, 256), backend="native")
    sky["sky.R"]                                        # a (256, 512) float16 array, as the EXR stores it
    fractalbake.bake("sky.json", "sky.exr", sets=["seed=9"])
    stats = fractalbake.compare("a.exr", "b.exr", max_abs="1e-3")

The arrays are the EXR's channels bit for bit: uint32 for UINT channels, float16 for HALF,
float32 for FLOAT, shaped (height, width). A scene is JSON text, a path, a dict, or None (the
default scene). Errors raise fractalbake.Error with the line the command line prints; arguments of
the wrong type or out of range raise TypeError, ValueError or OverflowError before anything is
done. A progress callback progress(fraction) may return True to stop the bake; an exception it
raises stops the bake and is raised again by the call; Ctrl-C stops it too, within a strip of rows
(no file is left) and raises KeyboardInterrupt. The bake runs on a thread of its own while the
calling thread waits for it, so that signals reach Python. A call into a context from its own
progress callback raises fractalbake.Error (a context runs one call at a time). The library is found
at FRACTALBAKE_LIBRARY, else where `cmake --install` put it beside this module, else by the loader's
search.
"""
import ctypes
import json
import numbers
import os
import threading

import numpy as np

__all__ = ["Context", "Error", "render", "bake", "read", "compare", "api", "version"]

API = 1
_UINT, _HALF, _FLOAT = 0, 1, 2
_DTYPES = {_UINT: np.uint32, _HALF: np.float16, _FLOAT: np.float32}
ERR_CANCELLED = 9


class Error(Exception):
    """A failed call: str() is the command line's line; .code the library's code (1 usage, 2 input,
    3 I/O, ..., 9 cancelled)."""

    def __init__(self, message, code):
        super().__init__(message)
        self.code = code


def _library_path():
    path = os.environ.get("FRACTALBAKE_LIBRARY")
    if path:
        return path
    try:
        from ._where import LIBRARY
        if os.path.exists(LIBRARY):
            return LIBRARY
    except ImportError:
        pass
    return "libfractalbake.so.0"


class _Desc(ctypes.Structure):
    _fields_ = [("api", ctypes.c_int), ("backend", ctypes.c_char_p), ("device", ctypes.c_char_p),
                ("threads", ctypes.c_int), ("max_memory", ctypes.c_uint64), ("tmpdir", ctypes.c_char_p)]


class _CompareDesc(ctypes.Structure):
    _fields_ = [(name, ctypes.c_char_p) for name in
                ("layer", "max_abs", "fail_percent", "warn", "warn_percent", "rmse", "psnr", "ssim")] + \
               [("flip", ctypes.c_int), ("ignore_missing", ctypes.c_int)]


_PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, ctypes.c_void_p)
_lib = None
_lib_lock = threading.Lock()


def _load():
    global _lib
    with _lib_lock:
        if _lib is not None:
            return _lib
        lib = ctypes.CDLL(_library_path())
        P, I, S = ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p
        PP = ctypes.POINTER(ctypes.c_void_p)
        IP = ctypes.POINTER(ctypes.c_int)
        sig = {
            "fractalbake_api": (I, []),
            "fractalbake_version": (S, []),
            "fractalbake_context_create": (I, [ctypes.POINTER(_Desc), PP]),
            "fractalbake_context_destroy": (None, [P]),
            "fractalbake_error": (S, [P]),
            "fractalbake_backend": (S, [P]),
            "fractalbake_device": (S, [P]),
            "fractalbake_set_progress": (None, [P, _PROGRESS, P]),
            "fractalbake_scene_load": (I, [P, S, S, ctypes.POINTER(S), I, PP]),
            "fractalbake_scene_destroy": (None, [P]),
            "fractalbake_bake": (I, [P, P, S, IP]),
            "fractalbake_render": (I, [P, P, IP, PP]),
            "fractalbake_open": (I, [P, S, PP]),
            "fractalbake_image_window": (None, [P, IP, IP, IP, IP, IP, IP]),
            "fractalbake_image_channels": (I, [P]),
            "fractalbake_image_channel": (S, [P, I]),
            "fractalbake_image_type": (I, [P, I]),
            "fractalbake_image_read": (I, [P, P, PP]),
            "fractalbake_image_destroy": (None, [P]),
            "fractalbake_compare": (I, [P, S, S, ctypes.POINTER(_CompareDesc), PP, IP]),
            "fractalbake_free": (None, [P]),
        }
        for name, (res, args) in sig.items():
            f = getattr(lib, name)
            f.restype, f.argtypes = res, args
        if lib.fractalbake_api() != API:
            raise ImportError(f"fractalbake: the library offers API {lib.fractalbake_api()}, this module needs {API}")
        _lib = lib
        return lib


def api():
    return _load().fractalbake_api()


def version():
    return _load().fractalbake_version().decode()


def _b(s):
    return None if s is None else str(s).encode()


# ---- Arguments, checked before any C call: ctypes would wrap an integer silently (2**32 + 4 is 4)
# and cut a string at its first NUL. The limits are the command line's. ----

_INT_MAX = 2 ** 31 - 1
_MAX_DIM = 65536


def _text(name, v, none=False):
    """A str (or os.PathLike when a path) without NUL bytes."""
    if v is None and none:
        return None
    if isinstance(v, os.PathLike):
        v = os.fspath(v)
    if isinstance(v, bytes) or not isinstance(v, str):
        raise TypeError(f"fractalbake: {name}: expected a str, found {type(v).__name__} {v!r}")
    if "\0" in v:
        raise ValueError(f"fractalbake: {name}: {v!r} holds a NUL character")
    return v


def _int(name, v, lo, hi, expected, c_max=_INT_MAX):
    """An int (not a bool) in lo..hi; beyond what the C argument holds (c_max) is OverflowError."""
    if isinstance(v, bool) or not isinstance(v, numbers.Integral):
        raise TypeError(f"fractalbake: {name}: expected an integer, found {type(v).__name__} {v!r}")
    v = int(v)
    if v > c_max or v < -c_max - 1:
        raise OverflowError(f"fractalbake: {name} {v}: does not fit the C argument ({expected})")
    if not lo <= v <= hi:
        raise ValueError(f"fractalbake: {name} {v}: expected {expected}")
    return v


def _context_args(backend, device, threads, max_memory):
    backend = _text("backend", backend)
    if device is not None and (isinstance(device, bool) or not isinstance(device, (str, numbers.Integral))):
        raise TypeError(f"fractalbake: device: expected an index or a name, found {type(device).__name__} {device!r}")
    threads = _int("threads", threads, 0, 1024, "0 (one per core) or 1..1024, as --threads")
    max_memory = _int("max_memory", max_memory, 0, int(9e18),
                      "0 (80% of the memory) or 1 MiB to 9e18 bytes, as --max-memory", c_max=2 ** 64 - 1)
    if 0 < max_memory < 1 << 20:
        raise ValueError(f"fractalbake: max_memory {max_memory}: expected 0 (80% of the memory) or 1 MiB to 9e18 "
                         "bytes, as --max-memory")
    return backend, None if device is None else str(device), threads, max_memory


def _sets(sets):
    if sets is None:
        return []
    if isinstance(sets, (str, bytes)) or not hasattr(sets, "__iter__"):
        raise TypeError(f"fractalbake: sets: expected a list of \"KEY.PATH=VALUE\" strings, found "
                        f"{type(sets).__name__} {sets!r}")
    out = list(sets)
    for i, v in enumerate(out):
        if not isinstance(v, str):
            raise TypeError(f"fractalbake: sets[{i}]: expected a \"KEY.PATH=VALUE\" string such as \"seed=9\", "
                            f"found {type(v).__name__} {v!r}")
        _text(f"sets[{i}]", v)
    return out


def _size(size):
    if size is None:
        return None
    if isinstance(size, bool) or not isinstance(size, (numbers.Integral, tuple, list)) or \
            (not isinstance(size, numbers.Integral) and len(size) != 2):
        raise TypeError(f"fractalbake: size: expected W or (W, H), found {type(size).__name__} {size!r}")
    w, h = (size, size // 2) if isinstance(size, numbers.Integral) else size
    return (_int("size[0]", w, 1, _MAX_DIM, f"a width in 1..{_MAX_DIM}"),
            _int("size[1]", h, 1, _MAX_DIM, f"a height in 1..{_MAX_DIM}"))


def _region_arg(region):
    if region is None:
        return None
    if isinstance(region, (str, bytes)) or not hasattr(region, "__len__") or len(region) != 4:
        raise TypeError(f"fractalbake: region: expected (x, y, w, h), found {type(region).__name__} {region!r}")
    names = ("x", "y", "w", "h")
    return [_int(f"region[{i}] ({names[i]})", v, 0 if i < 2 else 1, _INT_MAX if i < 2 else _MAX_DIM,
                 "x, y >= 0" if i < 2 else f"w, h in 1..{_MAX_DIM}") for i, v in enumerate(region)]


def _progress_arg(progress):
    if progress is not None and not callable(progress):
        raise TypeError(f"fractalbake: progress: expected a callable or None, found {type(progress).__name__}")
    return progress


def _scene_arg(scene):
    if scene is None or isinstance(scene, dict):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return _text("scene", scene)
    raise TypeError(f"fractalbake: scene: JSON text, a path, a dict or None (the default scene), found "
                    f"{type(scene).__name__}")


class Context:
    """A backend of its own ("auto", "vulkan" or "native"; a device; threads; a memory limit in
    bytes), used by one thread at a time (a lock sees to it). Contexts share nothing."""

    def __init__(self, backend="auto", device=None, threads=0, max_memory=0, tmpdir=None):
        self._ptr = None
        backend, device, threads, max_memory = _context_args(backend, device, threads, max_memory)
        tmpdir = _text("tmpdir", tmpdir, none=True)
        lib = _load()
        self._lib, self._lock = lib, threading.Lock()
        self._callback = set()  # the threads running this context's progress callback now
        self._ptr = ctypes.c_void_p()
        desc = _Desc(API, _b(backend), _b(device), threads, max_memory,
                     _b(tmpdir or os.environ.get("TMPDIR") or "/tmp"))
        rc = lib.fractalbake_context_create(ctypes.byref(desc), ctypes.byref(self._ptr))
        if rc:
            message = lib.fractalbake_error(self._ptr).decode() if self._ptr else "fractalbake: out of memory"
            lib.fractalbake_context_destroy(self._ptr)
            self._ptr = None
            raise Error(message, rc)

    @property
    def backend(self):
        return self._lib.fractalbake_backend(self._ptr).decode()

    @property
    def device(self):
        return self._lib.fractalbake_device(self._ptr).decode()

    def close(self):
        if self._ptr and threading.get_ident() in self._callback:
            raise Error("fractalbake: close: called from the context's own progress callback: close it after the "
                        "call returns", 1)
        if self._ptr:
            self._lib.fractalbake_context_destroy(self._ptr)
            self._ptr = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _check(self, rc):
        if rc:
            raise Error(self._lib.fractalbake_error(self._ptr).decode(), rc)

    def _enter(self, what):
        """The context's lock for a call; a call from its own progress callback is refused (the lock
        is held by the call the callback belongs to: waiting would never end)."""
        if threading.get_ident() in self._callback:
            raise Error(f"fractalbake: {what}: the context is running another call (this one came from its "
                        "progress callback): a context runs one call at a time", 1)
        if not self._ptr:
            raise Error(f"fractalbake: {what}: the context is closed", 1)
        return self._lock

    @staticmethod
    def _args(scene, size, sets, region, progress):
        """Every argument of a bake checked (types, ranges) before any C call."""
        return _scene_arg(scene), _size(size), _sets(sets), _region_arg(region), _progress_arg(progress)

    def _scene(self, scene, size, sets):
        sets = list(sets)
        if size is not None:
            sets.insert(0, f"size={size[0]}x{size[1]}")
        text = path = None
        if isinstance(scene, dict):
            text = json.dumps(scene)
        elif scene is not None:
            if scene.lstrip().startswith("{"):
                text = scene
            else:
                path = scene
        arr = (ctypes.c_char_p * max(1, len(sets)))(*[_b(s) for s in sets])
        out = ctypes.c_void_p()
        self._check(self._lib.fractalbake_scene_load(self._ptr, _b(text), _b(path), arr, len(sets),
                                                     ctypes.byref(out)))
        return out

    def _call(self, fn, progress):
        """fn() on a thread of its own, the progress callback set, while this thread waits: Ctrl-C
        (KeyboardInterrupt, or any exception a signal handler raises here) and an exception raised by
        the callback stop the bake at its next strip; once it has stopped (no file left), that
        exception is raised."""
        stop, caught, done, result = [], [], threading.Event(), {}

        def poll(fraction, _user):
            if stop or caught:
                return 1
            me = threading.get_ident()
            self._callback.add(me)
            try:
                return 1 if progress is not None and progress(fraction) else 0
            except BaseException as e:  # the call raises it once the bake has stopped
                caught.append(e)
                return 1
            finally:
                self._callback.discard(me)

        def work():
            try:
                result["rc"] = fn()
            except BaseException as e:  # pragma: no cover (ctypes raises nothing here)
                caught.append(e)
            finally:
                done.set()

        cb = _PROGRESS(poll)
        self._lib.fractalbake_set_progress(self._ptr, cb, None)
        worker = threading.Thread(target=work, name="fractalbake bake", daemon=True)
        try:
            worker.start()
            while not done.is_set():
                try:
                    done.wait(0.05)
                except BaseException as e:  # a signal's exception: stop the bake, wait for it
                    if not stop:
                        stop.append(e)
            worker.join()
        finally:
            self._lib.fractalbake_set_progress(self._ptr, _PROGRESS(), None)
        if stop:
            raise stop[0]
        if caught:
            raise caught[0]
        self._check(result["rc"])
    @staticmethod
    def _region(region):
        return None if region is None else (ctypes.c_int * 4)(*region)

    def _planes(self, img):
        lib = self._lib
        w, h = ctypes.c_int(), ctypes.c_int()
        lib.fractalbake_image_window(img, None, None, ctypes.byref(w), ctypes.byref(h), None, None)
        n = lib.fractalbake_image_channels(img)
        names = [lib.fractalbake_image_channel(img, c).decode() for c in range(n)]
        types = [lib.fractalbake_image_type(img, c) for c in range(n)]
        bufs = [np.empty((h.value, w.value), np.uint32 if t == _UINT else np.float32) for t in types]
        ptrs = (ctypes.c_void_p * max(1, n))(*[b.ctypes.data for b in bufs])
        self._check(lib.fractalbake_image_read(self._ptr, img, ptrs))
        # a half converts to float exactly, and back
        return {name: b.astype(np.float16) if t == _HALF else b for name, t, b in zip(names, types, bufs)}

    def render(self, scene=None, size=None, sets=(), region=None, progress=None):
        """The scene's channels as {name: array}, bit for bit those of `fractalbake render`."""
        scene, size, sets, region, progress = self._args(scene, size, sets, region, progress)
        with self._enter("render"):
            sc = self._scene(scene, size, sets)
            img = ctypes.c_void_p()
            try:
                self._call(lambda: self._lib.fractalbake_render(self._ptr, sc, self._region(region),
                                                                ctypes.byref(img)), progress)
                return self._planes(img)
            finally:
                self._lib.fractalbake_image_destroy(img)
                self._lib.fractalbake_scene_destroy(sc)

    def bake(self, scene, path, size=None, sets=(), region=None, progress=None):
        """`fractalbake render SCENE -o PATH`: the EXR (and the files the scene names) in place together."""
        scene, size, sets, region, progress = self._args(scene, size, sets, region, progress)
        path = _text("path", path)
        with self._enter("bake"):
            sc = self._scene(scene, size, sets)
            try:
                self._call(lambda: self._lib.fractalbake_bake(self._ptr, sc, _b(path), self._region(region)),
                           progress)
            finally:
                self._lib.fractalbake_scene_destroy(sc)

    def read(self, path):
        """An EXR file's channels as {name: array}."""
        path = _text("path", path)
        with self._enter("read"):
            img = ctypes.c_void_p()
            try:
                self._check(self._lib.fractalbake_open(self._ptr, _b(path), ctypes.byref(img)))
                return self._planes(img)
            finally:
                self._lib.fractalbake_image_destroy(img)

    def compare(self, a, b, layer=None, max_abs=None, fail_percent=None, warn=None, warn_percent=None, rmse=None,
                psnr=None, ssim=None, flip=False, ignore_missing=False):
        """`fractalbake compare --json A B` (thresholds as its flags take them) as a dict: per channel
        statistics and verdicts; ["result"] is the verdict."""
        a, b = _text("a", a), _text("b", b)
        limits = {"layer": layer, "max_abs": max_abs, "fail_percent": fail_percent, "warn": warn,
                  "warn_percent": warn_percent, "rmse": rmse, "psnr": psnr, "ssim": ssim}
        for name, v in limits.items():
            if v is not None and (isinstance(v, bool) or not isinstance(v, (str, numbers.Real))):
                raise TypeError(f"fractalbake: {name}: expected a str or a number, found {type(v).__name__} {v!r}")
            if v is not None:
                _text(name, str(v))
        with self._enter("compare"):
            d = _CompareDesc(*[_b(limits[k]) for k in limits], int(bool(flip)), int(bool(ignore_missing)))
            text, passed = ctypes.c_void_p(), ctypes.c_int()
            self._check(self._lib.fractalbake_compare(self._ptr, _b(a), _b(b), ctypes.byref(d),
                                                      ctypes.byref(text), ctypes.byref(passed)))
            try:
                return json.loads(ctypes.string_at(text.value).decode())
            finally:
                self._lib.fractalbake_free(text)


_contexts = {}
_contexts_lock = threading.Lock()


def _context(backend="auto", device=None, threads=0, max_memory=0):
    """One context per backend and settings, opened when first used and kept for the process."""
    key = _context_args(backend, device, threads, max_memory)
    with _contexts_lock:
        if key not in _contexts:
            _contexts[key] = Context(*key)
        return _contexts[key]


def render(scene=None, size=None, backend="auto", sets=(), region=None, progress=None, device=None, threads=0,
           max_memory=0):
    """The scene's channels as {name: numpy array} (no scene: the embedded default scene); size
    (W, H) overrides the scene's; sets are --set overrides ("seed=9")."""
    return _context(backend, device, threads, max_memory).render(scene, size, sets, region, progress)


def bake(scene, path, size=None, backend="auto", sets=(), region=None, progress=None, device=None, threads=0,
         max_memory=0):
    """Bakes the scene into the EXR file at path, as `fractalbake render SCENE -o PATH`."""
    _context(backend, device, threads, max_memory).bake(scene, path, size, sets, region, progress)


def read(path):
    """An EXR file's channels as {name: numpy array}."""
    return _context("native").read(path)


def compare(a, b, **thresholds):
    """Two EXR or PNG files compared as `fractalbake compare --json A B`: a dict of statistics."""
    return _context("native").compare(a, b, **thresholds)
