# The Python package implicit_sim (python/implicit_sim), installed by catkin_python_setup(); its compiled part
# implicit_sim._core is built by CMakeLists.txt (src/python).
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["implicit_sim"], package_dir={"": "python"}))
