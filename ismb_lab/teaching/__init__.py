"""The course around the notebooks: exercise checks, the nbgrader course, its exchange and the class
hub's servers.  Nothing is imported here: the hub and nbgrader load single modules of it, not the
network or OpenCV.
"""
