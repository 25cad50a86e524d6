"""The installed extension: one abi3 module whose NEEDED holds no GL library and no
libpython (EGL and OSMesa are loaded at run time, as the command line does, so libglvnd's
vendor dispatch keeps working and auditwheel accepts it)."""

import re
import shutil
import subprocess

import pytest

import arbvis._arbvis as extension


def test_the_module_is_abi3():
    assert extension.__file__.endswith(".abi3.so"), extension.__file__


@pytest.mark.skipif(shutil.which("readelf") is None, reason="binutils' readelf not installed")
def test_needed_holds_no_gl_library_and_no_libpython():
    out = subprocess.run(
        ["readelf", "-d", extension.__file__], capture_output=True, text=True, check=True
    ).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", out)
    assert needed, out
    for library in needed:
        assert not re.match(r"lib(GL|EGL|GLX|OpenGL|OSMesa|gbm|python)", library), needed
