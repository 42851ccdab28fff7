"""The figures: a run's plots (:mod:`.registry` names them, :mod:`.plots`, :mod:`.gait_diagram`,
:mod:`.strobe`, :mod:`.body_plots`), walk.gif (:mod:`.animation`, its pixels :mod:`.gif_pixels`
and file :mod:`.gif_file`), the figures of ``compare``, ``sweep`` and ``reproduce``
(:mod:`.compare_plot`, :mod:`.sweep_plot`, :mod:`.paper_figures`), their shared style
(:mod:`.plot_style`) and the process pool that draws a run's on every core (:mod:`.render_pool`).

They draw from results alone (:class:`klaw_ocp.result_files.RunData`) and never import a solver;
matplotlib is imported only by the drawing modules, on first use (not by this package or its
registry)."""
