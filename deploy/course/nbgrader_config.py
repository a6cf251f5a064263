"""The class's nbgrader course: handing out notebooks and collecting the students' work.

Students' servers and the teacher's shell find this file through JUPYTER_CONFIG_PATH
(deploy/course/README.md). Only two values are meant to change, by environment variable:

* ISMB_COURSE_ID: the course's id (default ``ismb_lab``);
* ISMB_NBGRADER_EXCHANGE: the exchange folder every account reaches
  (default ``/srv/nbgrader/exchange``; created by the teacher's setup, README).
"""

import os

c = get_config()  # noqa: F821  (nbgrader's config loader provides it)

c.CourseDirectory.course_id = os.environ.get("ISMB_COURSE_ID", "ismb_lab")
c.Exchange.root = os.environ.get("ISMB_NBGRADER_EXCHANGE", "/srv/nbgrader/exchange")
# A fetched assignment lands in ./labels, where the notebook's labeller saves its targets file.
c.Exchange.path_includes_course = False
# Lock files and half-written temporary files of a save are not work to hand in.
c.CourseDirectory.ignore = [".ipynb_checkpoints", "*.pyc", "__pycache__", "feedback", ".*.lock", ".*.tmp"]
# Submissions readable by their owner and the teacher's group only, filed under the account
# that handed them in (ismb_lab/teaching/exchange.py).
c.ExchangeFactory.submit = "ismb_lab.teaching.exchange.PrivateSubmit"
c.ExchangeFactory.collect = "ismb_lab.teaching.exchange.OwnerCollect"
# Every collect takes each student's latest submission, also one handed in after an earlier
# collect (nbgrader skips it otherwise: "Submission already exists, use --update").
c.ExchangeCollect.update = True
# A released assignment holds no ground truth of a pair that none of its notebooks reads: the
# labels assignment goes out without the answer key its students are asked to label.
c.ExchangeFactory.release_assignment = "ismb_lab.teaching.exchange.KeylessRelease"
# The exercise assignments keep a runnable first try beside each solution: the student
# version gets a comment in the solution's place, not nbgrader's raise NotImplementedError(),
# so it still runs on Restart & Run All (ismb_lab.teaching.course.CODE_STUB).
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE"}
# The longest notebook (07) has cells of tens of seconds on a loaded 2-core server.
c.Execute.timeout = 600
# Feedback shows each test's score and its error's last line, never the hidden tests (nbgrader
# shows them by design; a student could pass them on): ismb_lab/teaching/exchange.py.
from nbconvert.preprocessors import CSSHTMLHeaderPreprocessor  # noqa: E402
from nbgrader.preprocessors import GetGrades  # noqa: E402

from ismb_lab.teaching.exchange import FeedbackWithoutTests  # noqa: E402

c.GenerateFeedback.preprocessors = [FeedbackWithoutTests, GetGrades, CSSHTMLHeaderPreprocessor]
