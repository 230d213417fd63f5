"""fractalbake in Python: bakes in-process through libfractalbake, channels as numpy arrays.

    import fractalbake
    planes = fractalbake.render()                       # the embedded default scene
    sky = fractalbake.render("sky.json", size=(512, 256), backend="native")
    sky["sky.R"]                                        # a (256, 512) float16 array, as the EXR stores it
    fractalbake.bake("sky.json", "sky.exr", sets=["seed=9"])
    stats = fractalbake.compare("a.exr", "b.exr", max_abs="1e-3")

The arrays are the EXR's channels bit for bit: uint32 for UINT channels, float16 for HALF,
float32 for FLOAT, shaped (height, width). A scene is JSON text, a path, a dict, or None (the
default scene). Errors raise fractalbake.Error with the line the command line prints. A progress
callback progress(fraction) may return True to stop the bake; Ctrl-C stops it too, cleanly (no file
is left) and raises KeyboardInterrupt. The library is found at FRACTALBAKE_LIBRARY, else where
`cmake --install` put it beside this module, else by the loader's search.
"""
import ctypes
import json
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


class Context:
    """A backend of its own ("auto", "vulkan" or "native"; a device; threads; a memory limit in
    bytes), used by one thread at a time (a lock sees to it). Contexts share nothing."""

    def __init__(self, backend="auto", device=None, threads=0, max_memory=0, tmpdir=None):
        lib = _load()
        self._lib, self._lock = lib, threading.Lock()
        self._ptr = ctypes.c_void_p()
        desc = _Desc(API, _b(backend), _b(device), int(threads), int(max_memory),
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

    def _scene(self, scene, size, sets):
        sets = list(sets or [])
        if size is not None:
            w, h = (size, size // 2) if isinstance(size, int) else size
            sets.insert(0, f"size={int(w)}x{int(h)}")
        text = path = None
        if isinstance(scene, dict):
            text = json.dumps(scene)
        elif isinstance(scene, (str, os.PathLike)):
            if isinstance(scene, str) and scene.lstrip().startswith("{"):
                text = scene
            else:
                path = os.fspath(scene)
        elif scene is not None:
            raise TypeError("scene: JSON text, a path, a dict or None (the default scene)")
        arr = (ctypes.c_char_p * max(1, len(sets)))(*[_b(s) for s in sets])
        out = ctypes.c_void_p()
        self._check(self._lib.fractalbake_scene_load(self._ptr, _b(text), _b(path), arr, len(sets),
                                                     ctypes.byref(out)))
        return out

    def _call(self, fn, progress):
        """fn() with the progress callback set; Ctrl-C (or an exception in progress) stops the bake."""
        caught = []

        def poll(fraction, _user):
            try:
                return 1 if progress is not None and progress(fraction) else 0
            except BaseException as e:  # KeyboardInterrupt lands here: the bake stops, then it is raised
                caught.append(e)
                return 1

        cb = _PROGRESS(poll)
        self._lib.fractalbake_set_progress(self._ptr, cb, None)
        try:
            rc = fn()
        finally:
            self._lib.fractalbake_set_progress(self._ptr, _PROGRESS(), None)
        if caught:
            raise caught[0]
        self._check(rc)

    @staticmethod
    def _region(region):
        return None if region is None else (ctypes.c_int * 4)(*[int(v) for v in region])

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
        with self._lock:
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
        with self._lock:
            sc = self._scene(scene, size, sets)
            try:
                self._call(lambda: self._lib.fractalbake_bake(self._ptr, sc, _b(os.fspath(path)),
                                                              self._region(region)), progress)
            finally:
                self._lib.fractalbake_scene_destroy(sc)

    def read(self, path):
        """An EXR file's channels as {name: array}."""
        with self._lock:
            img = ctypes.c_void_p()
            try:
                self._check(self._lib.fractalbake_open(self._ptr, _b(os.fspath(path)), ctypes.byref(img)))
                return self._planes(img)
            finally:
                self._lib.fractalbake_image_destroy(img)

    def compare(self, a, b, layer=None, max_abs=None, fail_percent=None, warn=None, warn_percent=None, rmse=None,
                psnr=None, ssim=None, flip=False, ignore_missing=False):
        """`fractalbake compare --json A B` (thresholds as its flags take them) as a dict: per channel
        statistics and verdicts; ["result"] is the verdict."""
        with self._lock:
            d = _CompareDesc(*[_b(v) for v in (layer, max_abs, fail_percent, warn, warn_percent, rmse, psnr, ssim)],
                             int(bool(flip)), int(bool(ignore_missing)))
            text, passed = ctypes.c_void_p(), ctypes.c_int()
            self._check(self._lib.fractalbake_compare(self._ptr, _b(os.fspath(a)), _b(os.fspath(b)), ctypes.byref(d),
                                                      ctypes.byref(text), ctypes.byref(passed)))
            try:
                return json.loads(ctypes.string_at(text.value).decode())
            finally:
                self._lib.fractalbake_free(text)


_contexts = {}
_contexts_lock = threading.Lock()


def _context(backend="auto", device=None, threads=0, max_memory=0):
    """One context per backend and settings, opened when first used and kept for the process."""
    key = (backend, device, threads, max_memory)
    with _contexts_lock:
        if key not in _contexts:
            _contexts[key] = Context(backend, device, threads, max_memory)
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
