"""What a run leaves behind: the log and summary (report, recorder), the annotated video (overlay, text_layout,
video), the plots (timeline, plot). Outputs read Commands and traces; nothing below imports them.
"""
