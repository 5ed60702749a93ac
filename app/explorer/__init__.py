"""The explorer in the browser (viser): one package for everything that builds or drives a page.

* :mod:`.server`: :class:`Explorer` (the viser server) and :class:`ClientSession` (one browser's
  controllers around its shared state);
* :mod:`.session`: the state and results a browser's controllers share;
* one module per controller (``design_controller``, ``pose_controller``, ``workspace_controller``
  with its engine side ``workspace_job``, ``view_controller``, ``orientation_controller``,
  ``studies_controller``, ``share_controller``) and per panel (``panels``, ``numbers_panel``,
  ``legend``, ``joints_panel``, ``compare_panel``, ``paper_panel``, ``tilt_panel``,
  ``dexterous_panel``, ``optimize_panel``, ``plot_exports``);
* the 3-D scene (``scene``), the page gate (``pagehook``), the browser bridge (``jsbridge``) and
  plots created at their first figure, a page's first ones after its first shell is drawn
  (``lazy_plot``).

It depends on the core (:mod:`paraspace.kinematics`) and on the shared services of :mod:`paraspace.app`
(jobs, limits, URL state, text escaping, figures); nothing outside this package imports its modules
but the server start-up.
"""

from .server import ClientSession, Explorer, main

__all__ = ["ClientSession", "Explorer", "main"]
