-- One line per clip: what was ingested, how much of it was observed, filled and lifted, and how sure its depth is.
CREATE OR REPLACE VIEW clip_summary AS
SELECT
    c.clip_id,
    c.subject,
    c.skeleton,
    c.source_format,
    c.n_frames,
    c.n_joints,
    c.has_truth,
    c.gap_fill_method,
    c.lift_method,
    c.depth_ambiguous,
    round(c.depth_log_odds, 2) AS depth_log_odds,
    round(c.n_observed / (c.n_frames * c.n_joints), 4) AS observed_share,
    j.n_filled,
    j.n_lifted
FROM clips AS c
LEFT JOIN (
    SELECT clip_id,
           count(*) FILTER (WHERE filled) AS n_filled,
           count(z) AS n_lifted
    FROM joints_3d
    GROUP BY clip_id
) AS j USING (clip_id);
