-- Mean root-relative depth error and MPJPE per clip and lifting method (thesis Table 4.1, summarised).
CREATE OR REPLACE VIEW depth_error AS
SELECT
    clip_id,
    method,
    any_value(units) AS units,
    avg(dz_mean) AS dz_mean,
    max(dz_max) AS dz_max,
    sum(sign_accuracy * n_sign) / nullif(sum(n_sign), 0) AS sign_accuracy,
    avg(mpjpe) AS mpjpe
FROM validation_joint
GROUP BY clip_id, method;
